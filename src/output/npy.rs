//! Uncompressed `.npy` files of bytes, written in pieces. In: a path, a C-order uint8 array and
//! a function that sees each piece before it is written. Out: the file, byte for byte what
//! `ndarray-npy` writes for the array (its own header).

use crate::backend::Occupancy;
use crate::fsio::To;
use ndarray::{ArrayBase, Data, Dimension};
use ndarray_npy::WriteNpyExt;
use std::io::{self, Write};
use std::path::Path;

/// Bytes per `write_all`: small enough that the copy into the file's buffer reads a piece from
/// the cache `visit` just read it into; a multiple of 4,096.
pub const NPY_PIECE: usize = 1 << 18;

/// Write `a` (standard layout) as `path`, atomically, calling `visit` with each piece of its
/// elements in order (`NPY_PIECE` bytes, the last one shorter) just before it is written.
/// Returns the file's size.
pub fn write_npy_u8<S: Data<Elem = u8>, D: Dimension>(
    to: To,
    path: &Path,
    a: &ArrayBase<S, D>,
    mut visit: impl FnMut(&[u8]),
) -> io::Result<u64> {
    let data = a.as_slice().ok_or_else(|| io::Error::other("npy: array not in standard layout"))?;
    let header = npy_header(a, data.len())?;
    to.write_atomic(path, |w| {
        w.write_all(&header)?;
        for piece in data.chunks(NPY_PIECE) {
            visit(piece);
            w.write_all(piece)?;
        }
        Ok(())
    })
}

/// An occupancy grid's labels as an uncompressed `.npy` (uint8, C order, (400, 400, 32)),
/// atomically, through `write_npy_u8` (`visit` as there; a grid not in standard layout is
/// copied into it first). Returns the file's size.
pub fn write_occ_npy(to: To, path: &Path, occ: &Occupancy, visit: impl FnMut(&[u8])) -> io::Result<u64> {
    write_npy_u8(to, path, &occ.labels.as_standard_layout(), visit)
}

/// ndarray-npy's header for `a`: what its writer emits before the `data_len` bytes of elements,
/// which are counted, not copied.
fn npy_header<S: Data<Elem = u8>, D: Dimension>(a: &ArrayBase<S, D>, data_len: usize) -> io::Result<Vec<u8>> {
    struct Head {
        kept: Vec<u8>,
        total: usize,
    }
    impl Write for Head {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            let room = 4096usize.saturating_sub(self.kept.len()).min(buf.len());
            self.kept.extend_from_slice(&buf[..room]);
            self.total += buf.len();
            Ok(buf.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }
    let mut head = Head { kept: Vec::new(), total: 0 };
    a.write_npy(&mut head).map_err(|e| io::Error::other(format!("npy: {e}")))?;
    let len = head.total.checked_sub(data_len).filter(|&n| n <= head.kept.len());
    let len = len.ok_or_else(|| io::Error::other("npy: header longer than expected"))?;
    head.kept.truncate(len);
    Ok(head.kept)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same bytes as ndarray-npy's `write_npy`, and every element seen once, in order.
    #[test]
    fn pieces_make_the_file_ndarray_npy_writes() {
        let a = ndarray::Array3::<u8>::from_shape_fn((50, 400, 32), |(i, j, k)| ((i * 7 + j * 3 + k) % 9) as u8);
        let dir = std::env::temp_dir().join(format!("rocc-npy-pieces-{}", std::process::id()));
        let (ours, theirs) = (dir.join("ours.npy"), dir.join("theirs.npy"));
        let mut seen = Vec::new();
        let bytes = write_npy_u8(To::Now, &ours, &a, |p| seen.extend_from_slice(p)).expect("write");
        std::fs::create_dir_all(&dir).expect("dir");
        a.write_npy(std::fs::File::create(&theirs).expect("create")).expect("write_npy");
        let (x, y) = (std::fs::read(&ours).expect("read"), std::fs::read(&theirs).expect("read"));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(x, y);
        assert_eq!(bytes, y.len() as u64);
        assert_eq!(seen, a.as_slice().expect("standard layout"));
        assert!(a.len() > 2 * NPY_PIECE);
    }

    /// A grid in Fortran order is written in C order, the same file as its standard-layout copy,
    /// and reads back equal.
    #[test]
    fn a_grid_in_any_layout_writes_the_same_file() {
        use crate::backend::layout::{NX, NY, NZ};
        use ndarray::ShapeBuilder;
        let f = |(i, j, k): (usize, usize, usize)| ((i * 5 + j * 11 + k * 3) % 23) as u8;
        let c = Occupancy { labels: ndarray::Array3::from_shape_fn((NX, NY, NZ), f) };
        let fortran = Occupancy { labels: ndarray::Array3::from_shape_fn((NX, NY, NZ).f(), f) };
        assert!(!fortran.labels.is_standard_layout());
        let dir = std::env::temp_dir().join(format!("rocc-npy-layout-{}", std::process::id()));
        let (a, b) = (dir.join("c.npy"), dir.join("f.npy"));
        write_occ_npy(To::Now, &a, &c, |_| {}).expect("write");
        write_occ_npy(To::Now, &b, &fortran, |_| {}).expect("write");
        let (x, y) = (std::fs::read(&a).expect("read"), std::fs::read(&b).expect("read"));
        let back = crate::backend::read_npy(&b).expect("read back");
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(x, y);
        assert_eq!(back, c);
    }
}
