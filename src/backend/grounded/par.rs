//! Vectors written on all cores with no zero fill first: the CPU operations' outputs are tens of
//! megabytes (a `cpu-small` crop's logits are 38 MB), and `vec![0.0; n]` fills them on the
//! calling thread while the other cores wait, before the operation writes every element again.

use rayon::prelude::*;

/// Elements per task. A multiple of 9 (a row of labels) and of 32 (a column of voxels), so a
/// task's part starts on a row and on a column.
pub const CHUNK: usize = 4608;

/// `n` values; `fill(start, part)` writes elements `start..start + part.len()` (a task's part,
/// at most `CHUNK` long, starting at a multiple of `CHUNK`). Each part is filled in a buffer on
/// the task's stack (zeroed, in cache) and copied into the vector once.
pub fn par_vec(n: usize, fill: impl Fn(usize, &mut [f32]) + Sync) -> Vec<f32> {
    let mut out = Vec::with_capacity(n);
    out.spare_capacity_mut()[..n].par_chunks_mut(CHUNK).enumerate().for_each(|(task, part)| {
        let mut buf = [0f32; CHUNK];
        let buf = &mut buf[..part.len()];
        fill(task * CHUNK, buf);
        part.write_copy_of_slice(buf);
    });
    // SAFETY: the tasks' parts cover 0..n, and each wrote its whole part just above.
    unsafe { out.set_len(n) };
    out
}

/// `n` zeros, written on all cores.
pub fn par_zeros(n: usize) -> Vec<f32> {
    par_vec(n, |_, _| {})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_element_is_written_once_in_place() {
        for n in [0, 1, CHUNK - 1, CHUNK, 3 * CHUNK + 17] {
            let v = par_vec(n, |start, part| {
                for (i, x) in part.iter_mut().enumerate() {
                    *x = (start + i) as f32;
                }
            });
            assert_eq!(v.len(), n);
            assert!(v.iter().enumerate().all(|(i, &x)| x == i as f32), "n = {n}");
        }
    }
}
