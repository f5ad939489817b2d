//! Vectors written on all cores with no zero fill first: the CPU operations' outputs are tens of
//! megabytes (a `cpu-small` crop's logits are 38 MB), and `vec![0.0; n]` fills them on the
//! calling thread while the other cores wait, before the operation writes every element again.
//! Here each task zeroes its own part and fills it at once, while the part is in cache.

use rayon::prelude::*;
use std::mem::MaybeUninit;

/// Elements per task. A multiple of 9 (a row of labels) and of 32 (a column of voxels), so a
/// task's part starts on a row and on a column.
pub const CHUNK: usize = 4608;

/// A task's part of a vector being built, zeroed: the one place its memory becomes `f32`s.
fn zeroed(part: &mut [MaybeUninit<f32>]) -> &mut [f32] {
    part.fill(MaybeUninit::new(0.0));
    // SAFETY: every element was initialised just above, and `f32` has no invalid bit pattern.
    unsafe { &mut *(part as *mut [MaybeUninit<f32>] as *mut [f32]) }
}

/// `n` values; `fill(start, part)` writes elements `start..start + part.len()` (a task's part,
/// at most `CHUNK` long, starting at a multiple of `CHUNK`; zeroed when handed over).
pub fn par_vec(n: usize, fill: impl Fn(usize, &mut [f32]) + Sync) -> Vec<f32> {
    let lens: Vec<usize> = (0..n).step_by(CHUNK).map(|start| CHUNK.min(n - start)).collect();
    par_zeroed_parts(&lens, |task, part| fill(task * CHUNK, part))
}

/// Two vectors of `rows` rows, `wa` and `wb` values wide (each 1 to 9), filled together:
/// `fill(first_row, a_part, b_part)` writes a task's rows (at most `CHUNK / 9` of them, starting
/// at a multiple of that), as `par_vec` does.
pub fn par_vec2(
    rows: usize,
    [wa, wb]: [usize; 2],
    fill: impl Fn(usize, &mut [f32], &mut [f32]) + Sync,
) -> (Vec<f32>, Vec<f32>) {
    assert!((1..=9).contains(&wa) && (1..=9).contains(&wb), "widths {wa} and {wb}");
    const ROWS: usize = CHUNK / 9;
    let (mut a, mut b) = (Vec::with_capacity(rows * wa), Vec::with_capacity(rows * wb));
    let parts_a = a.spare_capacity_mut()[..rows * wa].par_chunks_mut(ROWS * wa);
    let parts_b = b.spare_capacity_mut()[..rows * wb].par_chunks_mut(ROWS * wb);
    parts_a.zip(parts_b).enumerate().for_each(|(task, (pa, pb))| fill(task * ROWS, zeroed(pa), zeroed(pb)));
    // SAFETY: both vectors' parts cover their first `rows * width` elements (the same number of
    // tasks, ROWS rows each), each initialised by `zeroed` above.
    unsafe {
        a.set_len(rows * wa);
        b.set_len(rows * wb);
    }
    (a, b)
}

/// Parts of the lengths `lens`, one after another in one vector: each task zeroes its part in
/// place and hands it to `f(part_index, part)`, so the zeros and `f`'s writes meet in cache
/// rather than in a zero fill of the whole vector first.
pub fn par_zeroed_parts(lens: &[usize], f: impl Fn(usize, &mut [f32]) + Sync) -> Vec<f32> {
    let n = lens.iter().sum();
    let mut out = Vec::with_capacity(n);
    let mut rest = &mut out.spare_capacity_mut()[..n];
    let mut parts = Vec::with_capacity(lens.len());
    for &len in lens {
        let (part, tail) = std::mem::take(&mut rest).split_at_mut(len);
        parts.push(part);
        rest = tail;
    }
    parts.into_par_iter().enumerate().for_each(|(i, part)| f(i, zeroed(part)));
    // SAFETY: the parts cover 0..n, each initialised by `zeroed` above.
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
        assert!(par_zeros(3 * CHUNK + 5).iter().all(|&x| x == 0.0));
        let v = par_zeroed_parts(&[3, 0, 5, 1], |i, part| {
            assert!(part.iter().all(|&x| x == 0.0));
            part.fill(i as f32);
        });
        assert_eq!(v, [0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 2.0, 2.0, 3.0]);
        for rows in [0, 5, 512, 513, 3000] {
            let (a, b) = par_vec2(rows, [9, 1], |r0, a, b| {
                for (i, x) in a.iter_mut().enumerate() {
                    *x = (r0 * 9 + i) as f32;
                }
                for (i, x) in b.iter_mut().enumerate() {
                    *x = -((r0 + i) as f32);
                }
            });
            assert_eq!((a.len(), b.len()), (9 * rows, rows));
            assert!(a.iter().enumerate().all(|(i, &x)| x == i as f32), "rows = {rows}");
            assert!(b.iter().enumerate().all(|(i, &x)| x == -(i as f32)), "rows = {rows}");
        }
    }
}
