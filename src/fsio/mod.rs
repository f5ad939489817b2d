//! Files written safely. In: a path and the bytes for it. Out: the file under its final name,
//! or no file at all. Every file rocc writes goes through `write_atomic` (or `Behind`, which
//! finishes the same work on a writer thread): to a temporary name in the same directory, then
//! renamed, so an interrupted run never leaves a truncated file under a final name and a re-run
//! can resume (no fsync: that protects against a crash of the process, not of the machine).
//! Also here: the sweep of the temporaries a killed run leaves, and the content hash that
//! manifests record (FNV-1a, also rocc's one hash for seeds and digests).

mod behind;
mod sink;

pub use behind::Behind;
pub use sink::Sink;

use std::fs;
use std::io;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Where a writer sends its file: through `write_atomic` now, or through a `Behind`.
#[derive(Clone, Copy, Default)]
pub enum To<'a> {
    #[default]
    Now,
    Behind(&'a Behind),
}

impl To<'_> {
    /// `write_atomic` or `Behind::write_atomic`.
    pub fn write_atomic(self, path: &Path, fill: impl FnOnce(&mut Sink) -> io::Result<()>) -> io::Result<u64> {
        match self {
            To::Now => write_atomic(path, fill),
            To::Behind(b) => b.write_atomic(path, fill),
        }
    }
}

/// Write `path` through `fill` under a temporary sibling name, then rename it into place; returns
/// the final size. Parent directories are created. The temporary file is removed on error.
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut Sink) -> io::Result<()>) -> io::Result<u64> {
    settle(filled(path, fill)?, path)
}

/// A sink for `path` under its temporary name (the directory created), filled by `fill`; on
/// error the temporary is removed.
fn filled(path: &Path, fill: impl FnOnce(&mut Sink) -> io::Result<()>) -> io::Result<Sink> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    fs::create_dir_all(dir)?;
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, format!("`{}` names no file", path.display())))?;
    // Unique per process and call, so parallel writers never share a temporary.
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = dir.join(format!(".{}.tmp-{}-{n}", name.to_string_lossy(), std::process::id()));
    let mut sink = Sink::new(&tmp);
    if let Err(e) = fill(&mut sink) {
        drop(sink);
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
    Ok(sink)
}

/// Write out what `sink` holds and rename its temporary to `path`; the temporary is removed on
/// error.
fn settle(sink: Sink, path: &Path) -> io::Result<u64> {
    let tmp = sink.tmp().to_path_buf();
    let result = sink.finish().and_then(|bytes| fs::rename(&tmp, path).map(|_| bytes));
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Whether `name` is one of `write_atomic`'s temporaries: `.{file}.tmp-{pid}-{n}`.
pub fn is_atomic_tmp(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('.') else { return false };
    let Some(at) = rest.rfind(".tmp-") else { return false };
    let mut parts = rest[at + 5..].split('-');
    let num = |p: Option<&str>| p.is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    at > 0 && num(parts.next()) && num(parts.next()) && parts.next().is_none()
}

/// Remove the temporaries an interrupted run left in `dir` and its sub-directories (a killed
/// process never reaches its clean-up). Call it only on a directory this process alone writes:
/// a clip's directory at the start of its compile (shards write different clips). Returns how
/// many were removed; a missing `dir` has none.
pub fn sweep_stale_tmp(dir: &Path) -> io::Result<usize> {
    let mut n = 0;
    let entries = match fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(e),
    };
    for e in entries {
        let e = e?;
        let ty = e.file_type()?;
        if ty.is_dir() {
            n += sweep_stale_tmp(&e.path())?;
        } else if ty.is_file() && is_atomic_tmp(&e.file_name().to_string_lossy()) {
            fs::remove_file(e.path())?;
            n += 1;
        }
    }
    Ok(n)
}

/// Content hash used in manifests: FNV-1a 64, hex, prefixed by its name. It identifies inputs
/// (did the file change?); it is not a cryptographic digest.
pub fn input_hash(bytes: &[u8]) -> String {
    format!("fnv1a64:{:016x}", fnv1a(bytes))
}

/// FNV-1a, 64 bit, of `bytes`: a stable hash of names and contents (seeds from names, the
/// manifest's content hash). Not a cryptographic digest.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    Fnv1a::new().write(bytes).finish()
}

/// FNV-1a, 64 bit, fed in pieces (`Tracks::digest` feeds it every pose bit for bit).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv1a {
    pub const fn new() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }

    pub fn write(&mut self, bytes: &[u8]) -> &mut Self {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
        self
    }

    /// `x`'s little-endian bytes.
    pub fn write_u64(&mut self, x: u64) -> &mut Self {
        self.write(&x.to_le_bytes())
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// A scratch directory of this test's own.
    fn scratch(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("rocc-fsio-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        d
    }

    /// Bytes that differ from position to position (a shifted or repeated chunk shows).
    fn pattern(n: usize, salt: u64) -> Vec<u8> {
        (0..n as u64).map(|i| (fnv1a(&(i ^ salt).to_le_bytes()) >> 7) as u8).collect()
    }

    /// Sizes around the block and chunk edges, fed in uneven pieces: the file holds exactly the
    /// bytes written (direct, buffered and streamed routes alike) and no temporary is left.
    #[test]
    fn write_atomic_keeps_every_byte_at_every_size() {
        every_size("sizes");
    }

    /// The same where the file system refuses direct I/O (tmpfs on older kernels).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn write_atomic_without_direct_io_keeps_every_byte() {
        sink::REFUSE_DIRECT.store(true, Ordering::Relaxed);
        every_size("buffered");
        sink::REFUSE_DIRECT.store(false, Ordering::Relaxed);
    }

    fn every_size(name: &str) {
        let dir = scratch(name);
        let (b, c) = (4096, 1 << 20);
        for (k, n) in [0, 1, b - 1, b, b + 1, c - 1, c, c + 1, 3 * c + 17, 33 * c + 5, 32 * c].into_iter().enumerate() {
            let want = pattern(n, k as u64);
            let path = dir.join(format!("f{k}.bin"));
            let size = write_atomic(&path, |w| {
                for piece in want.chunks(1 + (k * 7919) % 300_001) {
                    w.write_all(piece)?;
                }
                Ok(())
            })
            .expect("write");
            assert_eq!(size, n as u64);
            assert_eq!(fs::read(&path).expect("read"), want, "{n} bytes");
        }
        let left: Vec<_> = fs::read_dir(&dir).expect("dir").filter_map(|e| e.ok()).map(|e| e.file_name()).collect();
        assert_eq!(left.len(), 11, "{left:?}");
        let _ = fs::remove_dir_all(&dir);
    }

    /// A failing `fill` leaves neither the file nor its temporary, on both routes.
    #[test]
    fn a_failed_fill_leaves_nothing() {
        let dir = scratch("fail");
        let big = pattern(3 << 20, 1);
        let fill = |w: &mut Sink| -> io::Result<()> {
            std::io::Write::write_all(w, &big)?;
            Err(io::Error::other("no"))
        };
        assert!(write_atomic(&dir.join("a"), fill).is_err());
        let behind = Behind::new();
        assert!(behind.write_atomic(&dir.join("b"), fill).is_err());
        behind.finish().expect("nothing queued");
        assert_eq!(fs::read_dir(&dir).expect("dir").count(), 0);
        let _ = fs::remove_dir_all(&dir);
    }

    /// Files written behind the caller are all in place after `finish` (or a drop), with their
    /// bytes; a failure on the writer's side comes back from `finish` with the file's path.
    #[test]
    fn behind_writes_every_file_and_reports_failures() {
        let dir = scratch("behind");
        let sizes = [5_120_128, 2_456_272, 2_917_054, 18_592, 0, 1 << 20];
        let behind = Behind::new();
        for (k, &n) in sizes.iter().cycle().take(24).enumerate() {
            let bytes = pattern(n, k as u64);
            let got = To::Behind(&behind).write_atomic(&dir.join(format!("{k}")), |w| w.write_all(&bytes));
            assert_eq!(got.expect("queued"), n as u64);
        }
        behind.finish().expect("written");
        for (k, &n) in sizes.iter().cycle().take(24).enumerate() {
            assert_eq!(fs::read(dir.join(format!("{k}"))).expect("read"), pattern(n, k as u64));
        }
        // A drop waits too.
        {
            let behind = Behind::new();
            behind.write_atomic(&dir.join("dropped"), |w| w.write_all(&pattern(3 << 20, 9))).expect("queued");
        }
        assert_eq!(fs::read(dir.join("dropped")).expect("read"), pattern(3 << 20, 9));
        // The final name is a directory that is not empty: the rename fails on the writer.
        fs::create_dir_all(dir.join("taken").join("x")).expect("dir");
        let behind = Behind::new();
        behind.write_atomic(&dir.join("taken"), |w| w.write_all(&pattern(2 << 20, 3))).expect("queued");
        let err = behind.finish().expect_err("rename onto a directory");
        assert!(err.to_string().contains("taken"), "{err}");
        let tmps = fs::read_dir(&dir)
            .expect("dir")
            .filter_map(|e| e.ok())
            .filter(|e| is_atomic_tmp(&e.file_name().to_string_lossy()));
        assert_eq!(tmps.count(), 0);
        let _ = fs::remove_dir_all(&dir);
    }

    /// The published FNV-1a 64 test vectors, whole and fed in pieces.
    #[test]
    fn fnv1a_gives_the_reference_values() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
        assert_eq!(Fnv1a::new().write(b"foo").write(b"bar").finish(), fnv1a(b"foobar"));
        assert_eq!(Fnv1a::new().write_u64(7).finish(), fnv1a(&7u64.to_le_bytes()));
    }
}
