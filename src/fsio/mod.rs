//! Files written safely. In: a path and the bytes for it. Out: the file under its final name,
//! or no file at all. Every file rocc writes goes through `write_atomic`: to a temporary name in
//! the same directory, then renamed, so an interrupted run never leaves a truncated file under a
//! final name and a re-run can resume (no fsync: that protects against a crash of the process,
//! not of the machine). Also here: the sweep of the temporaries a killed run leaves, and the
//! content hash that manifests record (FNV-1a, also rocc's one hash for seeds and digests).

use std::fs::{self, File};
use std::io::{self, BufWriter};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Write `path` through `fill` under a temporary sibling name, then rename it into place; returns
/// the final size. Parent directories are created. The temporary file is removed on error.
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>) -> io::Result<u64> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    fs::create_dir_all(dir)?;
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, format!("`{}` names no file", path.display())))?;
    // Unique per process and call, so parallel writers never share a temporary.
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = dir.join(format!(".{}.tmp-{}-{n}", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        fill(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        let bytes = f.metadata()?.len();
        drop(f);
        fs::rename(&tmp, path)?;
        Ok(bytes)
    })();
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
