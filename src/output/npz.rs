//! The `.npz` container, written directly: a zip archive (no zip64, fixed 1980-01-01 timestamps,
//! so the bytes depend only on the arrays) of `.npy` v1.0 members, each raw-deflated by the
//! coder `DEFLATE` names: rocc's run coder (`runs.rs`), which codes runs of the previous byte
//! (as zlib's RLE strategy does) and checksums in the same pass. BEV arrays are mostly zeros: it
//! takes half the CPU of zlib-rs's RLE strategy for the same size, a quarter of `fdeflate`'s
//! (`bench npz` measures every coder here against zlib's levels; docs/benchmarks.md has the
//! figures). numpy's `np.load` and `ndarray_npy::NpzReader` read the result.

use super::runs::RunCoder;
use miniz_oxide::deflate::core::{
    CompressionStrategy, CompressorOxide, TDEFLFlush, TDEFLStatus, compress_to_output,
    create_comp_flags_from_zip_params,
};
use std::io::{self, Write};

/// An element type `.npy` can hold, and its `descr` (little-endian where it has an order).
pub trait NpyElem: bytemuck::Pod {
    const DESCR: &'static str;
}

impl NpyElem for i8 {
    const DESCR: &'static str = "|i1";
}

impl NpyElem for u8 {
    const DESCR: &'static str = "|u1";
}

impl NpyElem for i32 {
    const DESCR: &'static str = "<i4";
}

impl NpyElem for f32 {
    const DESCR: &'static str = "<f4";
}

/// `xs` as little-endian bytes: their memory itself on a little-endian machine.
#[cfg(target_endian = "little")]
fn le_bytes<'a, T: NpyElem>(xs: &'a [T], _buf: &'a mut Vec<u8>) -> &'a [u8] {
    bytemuck::cast_slice(xs)
}

#[cfg(target_endian = "big")]
fn le_bytes<'a, T: NpyElem>(xs: &'a [T], buf: &'a mut Vec<u8>) -> &'a [u8] {
    buf.clear();
    for x in xs {
        buf.extend(bytemuck::bytes_of(x).iter().rev());
    }
    buf
}

/// The `.npy` v1.0 header of a C-order array: magic, version, length, then the dict padded with
/// spaces to a 64-byte boundary and closed by a newline.
fn npy_header(descr: &str, shape: &[usize]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let shape = if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) };
    let mut dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut h = b"\x93NUMPY\x01\x00".to_vec();
    h.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    h.extend_from_slice(dict.as_bytes());
    h
}

/// One member as it goes into the archive.
struct Member {
    name: String,
    crc: u32,
    raw: u64,
    deflated: Vec<u8>,
}

/// Elements checksummed and deflated per step, so both passes find them in cache.
const STEP: usize = 1 << 16;

/// How members are deflated. `bench npz` measures each against zlib's levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Deflate {
    /// `fdeflate`: one fixed Huffman table for runs of zeros, no match search.
    Fdeflate,
    /// miniz_oxide at this level (1-3 in `bench npz`) with the RLE strategy: matches only at
    /// distance 1, so runs of any value cost a few bits, and dynamic Huffman tables. Level 1
    /// takes miniz_oxide's fast path, which does not look at the strategy (it is `Zlib(1)`).
    Rle(u8),
    /// miniz_oxide at this level with the default strategy: zlib's levels, raw deflate.
    Zlib(u8),
    /// zlib-rs (zlib-ng's coder, under `zip`) at this level with the RLE strategy: zlib's
    /// `deflate_rle`, which scans for runs of the previous byte and never hashes.
    ZlibRsRle(u8),
    /// rocc's own run coder (`runs.rs`): the runs zlib's RLE strategy finds, without its window,
    /// with the CRC-32 in the same pass.
    Runs,
}

/// The deflate rocc writes with: on BEV frames the run coder is the fastest coder here, its files
/// within 2x of zlib level 6's (docs/benchmarks.md, `bench npz`).
pub const DEFLATE: Deflate = Deflate::Runs;

/// One member's raw deflate stream being built.
enum Deflater {
    Fdeflate(fdeflate::Compressor<Vec<u8>>),
    Oxide(Box<CompressorOxide>, Vec<u8>),
    /// The coder, a scratch block it writes into, and what it wrote so far.
    ZlibRs(zlib_rs::Deflate, Box<[u8; SCRATCH]>, Vec<u8>),
    Runs(RunCoder),
}

/// Output block of the zlib-rs coder.
const SCRATCH: usize = 1 << 16;

impl Deflater {
    fn new(how: Deflate) -> io::Result<Self> {
        Ok(match how {
            Deflate::Fdeflate => Self::Fdeflate(fdeflate::Compressor::new(Vec::new())?),
            Deflate::Rle(level) => Self::oxide(level, CompressionStrategy::RLE),
            Deflate::Zlib(level) => Self::oxide(level, CompressionStrategy::Default),
            Deflate::ZlibRsRle(level) => {
                let config = zlib_rs::DeflateConfig {
                    level: level.into(),
                    window_bits: -15,
                    strategy: zlib_rs::Strategy::Rle,
                    ..zlib_rs::DeflateConfig::default()
                };
                Self::ZlibRs(zlib_rs::Deflate::new_with_config(config), Box::new([0; SCRATCH]), Vec::new())
            }
            Deflate::Runs => Self::Runs(RunCoder::default()),
        })
    }

    fn oxide(level: u8, strategy: CompressionStrategy) -> Self {
        // Negative window bits: a raw deflate stream, with no zlib header or trailer.
        let flags = create_comp_flags_from_zip_params(level.into(), -15, strategy as i32);
        Self::Oxide(Box::new(CompressorOxide::new(flags)), Vec::new())
    }

    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        match self {
            Self::Fdeflate(z) => z.write_data(bytes),
            Self::Oxide(z, out) => oxide_step(z, out, bytes, TDEFLFlush::None),
            Self::ZlibRs(z, buf, out) => zlib_rs_step(z, buf, out, bytes, zlib_rs::DeflateFlush::NoFlush),
            Self::Runs(z) => {
                z.write(bytes);
                Ok(())
            }
        }
    }

    /// The raw deflate stream, and the CRC-32 of the input when the coder computed it.
    fn finish(self) -> io::Result<(Vec<u8>, Option<u32>)> {
        if let Self::Runs(z) = self {
            let (raw, crc) = z.finish();
            return Ok((raw, Some(crc)));
        }
        let raw: io::Result<Vec<u8>> = match self {
            Self::Fdeflate(z) => {
                let zlib = z.finish()?;
                // A zlib stream is a 2-byte header, the raw deflate data a zip member holds,
                // and an Adler-32 trailer.
                Ok(zlib.get(2..zlib.len().saturating_sub(4)).unwrap_or_default().to_vec())
            }
            Self::Oxide(mut z, mut out) => {
                oxide_step(&mut z, &mut out, &[], TDEFLFlush::Finish)?;
                Ok(out)
            }
            Self::ZlibRs(mut z, mut buf, mut out) => {
                zlib_rs_step(&mut z, &mut buf, &mut out, &[], zlib_rs::DeflateFlush::Finish)?;
                Ok(out)
            }
            Self::Runs(_) => unreachable!("returned above"),
        };
        Ok((raw?, None))
    }
}

/// Feed `bytes` to miniz_oxide, appending what it emits to `out`.
fn oxide_step(z: &mut CompressorOxide, out: &mut Vec<u8>, bytes: &[u8], flush: TDEFLFlush) -> io::Result<()> {
    let (status, used) = compress_to_output(z, bytes, flush, |b| {
        out.extend_from_slice(b);
        true
    });
    let done = if flush == TDEFLFlush::Finish { TDEFLStatus::Done } else { TDEFLStatus::Okay };
    if status != done || used != bytes.len() {
        return Err(io::Error::other(format!("npz: deflate stopped ({status:?}, {used} of {} bytes)", bytes.len())));
    }
    Ok(())
}

/// Feed `bytes` to zlib-rs through `buf`, appending what it emits to `out`; with `Finish`, until
/// the stream is closed.
fn zlib_rs_step(
    z: &mut zlib_rs::Deflate,
    buf: &mut [u8; SCRATCH],
    out: &mut Vec<u8>,
    mut bytes: &[u8],
    flush: zlib_rs::DeflateFlush,
) -> io::Result<()> {
    let finish = flush == zlib_rs::DeflateFlush::Finish;
    loop {
        let (in0, out0) = (z.total_in(), z.total_out());
        let status =
            z.compress(bytes, &mut buf[..], flush).map_err(|e| io::Error::other(format!("npz: deflate: {e:?}")))?;
        let wrote = (z.total_out() - out0) as usize;
        out.extend_from_slice(&buf[..wrote]);
        bytes = &bytes[(z.total_in() - in0) as usize..];
        // Done when the input is taken and the block was not filled (more may be pending then).
        let drained = bytes.is_empty() && wrote < SCRATCH;
        if (finish && status == zlib_rs::Status::StreamEnd) || (!finish && drained) {
            return Ok(());
        }
        if status == zlib_rs::Status::BufError && wrote == 0 {
            return Err(io::Error::other("npz: deflate made no progress"));
        }
    }
}

/// An `.npz` being built in memory; `finish` writes it out.
pub struct Npz {
    members: Vec<Member>,
    deflate: Deflate,
}

impl Default for Npz {
    fn default() -> Self {
        Self::with_deflate(DEFLATE)
    }
}

impl Npz {
    /// An empty archive whose members `how` deflates.
    pub fn with_deflate(how: Deflate) -> Self {
        Self { members: Vec::new(), deflate: how }
    }

    /// Add `data` (C order, `shape`) as member `name.npy`.
    pub fn add<T: NpyElem>(&mut self, name: &str, shape: &[usize], data: &[T]) -> io::Result<()> {
        if shape.iter().product::<usize>() != data.len() {
            return Err(io::Error::other(format!("npz: `{name}` has {} elements, shape {shape:?}", data.len())));
        }
        let header = npy_header(T::DESCR, shape);
        let mut crc = crc32fast::Hasher::new();
        let mut z = Deflater::new(self.deflate)?;
        crc.update(&header);
        z.write(&header)?;
        let mut buf = Vec::new();
        // The run coder checksums as it codes, and its runs stop at the end of each slice.
        let own_crc = matches!(z, Deflater::Runs(_));
        let step = if own_crc { data.len().max(1) } else { STEP };
        for chunk in data.chunks(step) {
            let bytes = le_bytes(chunk, &mut buf);
            if !own_crc {
                crc.update(bytes);
            }
            z.write(bytes)?;
        }
        let (deflated, coder_crc) = z.finish()?;
        let raw = (header.len() + std::mem::size_of_val(data)) as u64;
        let crc = coder_crc.unwrap_or_else(|| crc.finalize());
        self.members.push(Member { name: format!("{name}.npy"), crc, raw, deflated });
        Ok(())
    }

    /// Write the archive: each member's local header and data, then the central directory.
    pub fn finish(self, w: &mut impl Write) -> io::Result<()> {
        let too_big = || io::Error::other("npz: a member over 4 GiB needs zip64, which rocc does not write");
        let u32_of = |n: u64| u32::try_from(n).map_err(|_| too_big());
        let mut offset = 0u64;
        let mut central = Vec::new();
        for m in &self.members {
            let (raw, packed) = (u32_of(m.raw)?, u32_of(m.deflated.len() as u64)?);
            let fixed = |sig: u32, out: &mut Vec<u8>| {
                out.extend_from_slice(&sig.to_le_bytes());
                if sig == CENTRAL {
                    out.extend_from_slice(&20u16.to_le_bytes()); // version made by
                }
                for v in [20u16, 0, 8, 0, DOS_DATE] {
                    out.extend_from_slice(&v.to_le_bytes()); // version needed, flags, deflate, time, date
                }
                for v in [m.crc, packed, raw] {
                    out.extend_from_slice(&v.to_le_bytes());
                }
                out.extend_from_slice(&(m.name.len() as u16).to_le_bytes());
                out.extend_from_slice(&0u16.to_le_bytes()); // extra field length
            };
            let mut local = Vec::with_capacity(30 + m.name.len());
            fixed(LOCAL, &mut local);
            local.extend_from_slice(m.name.as_bytes());
            w.write_all(&local)?;
            w.write_all(&m.deflated)?;
            fixed(CENTRAL, &mut central);
            for v in [0u16, 0, 0] {
                central.extend_from_slice(&v.to_le_bytes()); // comment length, disk, internal attributes
            }
            central.extend_from_slice(&0u32.to_le_bytes()); // external attributes
            central.extend_from_slice(&u32_of(offset)?.to_le_bytes());
            central.extend_from_slice(m.name.as_bytes());
            offset += (local.len() + m.deflated.len()) as u64;
        }
        let n = self.members.len() as u16;
        let mut end = Vec::with_capacity(22);
        end.extend_from_slice(&END.to_le_bytes());
        for v in [0u16, 0, n, n] {
            end.extend_from_slice(&v.to_le_bytes());
        }
        end.extend_from_slice(&u32_of(central.len() as u64)?.to_le_bytes());
        end.extend_from_slice(&u32_of(offset)?.to_le_bytes());
        end.extend_from_slice(&0u16.to_le_bytes()); // comment length
        w.write_all(&central)?;
        w.write_all(&end)
    }
}

const LOCAL: u32 = 0x0403_4b50;
const CENTRAL: u32 = 0x0201_4b50;
const END: u32 = 0x0605_4b50;
/// 1980-01-01, the earliest date zip can hold.
const DOS_DATE: u16 = (1 << 5) | 1;

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{Array1, Array3};
    use ndarray_npy::NpzReader;

    #[test]
    fn npz_reads_back_with_ndarray_npy() {
        let a = Array3::from_shape_fn((3, 50, 70), |(c, i, j)| ((c * 7 + i * j) % 5) as i8 - 2);
        let b = Array1::from_shape_fn(200_000, |i| if i % 1000 == 0 { -(i as i32) } else { 0 });
        let f = Array1::from_shape_fn(9, |i| i as f32 * 0.5);
        for how in [
            Deflate::Fdeflate,
            Deflate::Rle(1),
            Deflate::Rle(2),
            Deflate::Zlib(2),
            Deflate::ZlibRsRle(1),
            Deflate::Runs,
        ] {
            let mut npz = Npz::with_deflate(how);
            npz.add("a", &[3, 50, 70], a.as_slice().unwrap()).unwrap();
            npz.add("b", &[200_000], b.as_slice().unwrap()).unwrap();
            npz.add("f", &[9], f.as_slice().unwrap()).unwrap();
            let mut bytes = Vec::new();
            npz.finish(&mut bytes).unwrap();
            let mut r = NpzReader::new(std::io::Cursor::new(bytes)).unwrap();
            assert_eq!(r.names().unwrap(), vec!["a", "b", "f"], "{how:?}");
            let ra: Array3<i8> = r.by_name("a").unwrap();
            let rb: Array1<i32> = r.by_name("b").unwrap();
            let rf: Array1<f32> = r.by_name("f").unwrap();
            assert_eq!((&ra, &rb, &rf), (&a, &b, &f), "{how:?}");
        }
    }

    #[test]
    fn a_shape_that_does_not_match_the_data_is_an_error() {
        assert!(Npz::default().add("x", &[2, 3], &[0u8; 5]).is_err());
    }

    #[test]
    fn npy_headers_end_on_a_64_byte_boundary() {
        for shape in [&[18usize, 400, 400][..], &[5], &[400, 400, 32]] {
            let h = npy_header("<i4", shape);
            assert_eq!(h.len() % 64, 0);
            assert_eq!(*h.last().unwrap(), b'\n');
        }
    }
}
