//! The writer behind `write_atomic` and `Behind`. It gathers a file in aligned 1 MiB chunks; a
//! file that ends inside the first chunk is written the usual way, a larger one goes to the disk
//! with `O_DIRECT`, its chunks handed to the kernel in vectored writes, never through the page
//! cache. Why: on the machines measured (docs/benchmarks.md, "Writes") the kernel's copy into
//! freshly allocated page-cache pages costs about 1.7 ms of CPU per 10 MB, a quarter of a
//! 0.2 deg frame's CPU time, against a tenth of that for a direct write; a corpus is written once
//! and read later, so caching it only evicts what the user had in memory. Where the file system
//! refuses direct I/O (tmpfs, some network file systems) the same bytes go through the page
//! cache: the file's contents never depend on the route.

use std::fs::File;
use std::io::{self, IoSlice, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Direct I/O wants buffer addresses, offsets and lengths in multiples of the logical block
/// size: 4096 covers every block device in use (512-byte and 4K sectors).
const ALIGN: usize = 4096;
/// Bytes per chunk; a file that ends below this is written buffered (a direct write of a few
/// kilobytes would wait for the disk for nothing).
const CHUNK: usize = 1 << 20;
/// Chunks a sink holds before it writes them out itself (larger files stream).
const MAX_HELD: usize = 32;
/// Chunks kept for reuse: recycled memory is already mapped, so filling it costs no page faults.
const POOL_CAP: usize = 64;

static POOL: Mutex<Vec<Vec<u8>>> = Mutex::new(Vec::new());

/// Tests: open every file as a file system that refuses direct I/O would.
#[cfg(test)]
pub(super) static REFUSE_DIRECT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// `CHUNK` bytes starting on an `ALIGN` boundary inside `raw`.
struct Chunk {
    raw: Vec<u8>,
    start: usize,
}

impl Chunk {
    fn take() -> Self {
        let raw = POOL.lock().ok().and_then(|mut p| p.pop()).unwrap_or_else(|| vec![0; CHUNK + ALIGN]);
        let start = raw.as_ptr().align_offset(ALIGN);
        Chunk { raw, start }
    }

    fn bytes(&self, len: usize) -> &[u8] {
        &self.raw[self.start..self.start + len]
    }

    fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.raw[self.start..self.start + CHUNK]
    }
}

impl Drop for Chunk {
    fn drop(&mut self) {
        let raw = std::mem::take(&mut self.raw);
        if let Ok(mut p) = POOL.lock()
            && p.len() < POOL_CAP
        {
            p.push(raw);
        }
    }
}

/// The `io::Write` that `write_atomic`'s `fill` writes into. The file (the temporary name) is
/// created when the first chunks go out, or at `finish`.
pub struct Sink {
    path: PathBuf,
    /// Every chunk but the last is full.
    chunks: Vec<Chunk>,
    /// Bytes in the last chunk.
    last: usize,
    file: Option<File>,
    direct: bool,
    written: u64,
}

impl Sink {
    pub(super) fn new(path: &Path) -> Self {
        Sink { path: path.to_path_buf(), chunks: Vec::new(), last: CHUNK, file: None, direct: false, written: 0 }
    }

    /// The temporary name the sink writes.
    pub(super) fn tmp(&self) -> &Path {
        &self.path
    }

    /// The file's size so far.
    pub(super) fn len(&self) -> u64 {
        self.written + (self.chunks.len().saturating_sub(1) * CHUNK + self.held_last()) as u64
    }

    fn held_last(&self) -> usize {
        if self.chunks.is_empty() { 0 } else { self.last }
    }

    /// Write what is held and return the file's size.
    pub(super) fn finish(mut self) -> io::Result<u64> {
        let size = self.len();
        if self.file.is_none() && size < CHUNK as u64 {
            let mut f = File::create(&self.path)?;
            f.write_all(self.chunks.first().map_or(&[][..], |c| c.bytes(self.last)))?;
            return Ok(size);
        }
        let tail = self.held_last();
        let padded = tail.div_ceil(ALIGN) * ALIGN;
        if let Some(c) = self.chunks.last_mut() {
            // The tail goes out padded to a whole block; the file is cut to its size after.
            c.bytes_mut()[tail..padded].fill(0);
        }
        self.put(padded)?;
        if let Some(f) = &self.file
            && self.written != size
        {
            f.set_len(size)?;
        }
        Ok(size)
    }

    /// Write every chunk held (the last one's first `last_len` bytes) at the end of the file,
    /// opening it first if needed, and recycle them.
    fn put(&mut self, last_len: usize) -> io::Result<()> {
        if self.file.is_none() {
            let (f, direct) = open(&self.path)?;
            self.file = Some(f);
            self.direct = direct;
        }
        let n = self.chunks.len();
        let Some(f) = self.file.as_mut() else { return Ok(()) };
        let slices = || -> Vec<IoSlice> {
            let len = |i: usize| if i + 1 == n { last_len } else { CHUNK };
            self.chunks.iter().enumerate().map(|(i, c)| IoSlice::new(c.bytes(len(i)))).collect()
        };
        let mut all = slices();
        let total: usize = all.iter().map(|s| s.len()).sum();
        match write_all_vectored(f, &mut all) {
            // A file system that opened with O_DIRECT but refuses the write (EINVAL, mostly):
            // write these chunks again, buffered, from where the file stood. A failure for
            // another reason (a full disk) fails again there.
            Err(_) if self.direct => {
                self.direct = false;
                buffered(f)?;
                f.set_len(self.written)?;
                f.seek(io::SeekFrom::Start(self.written))?;
                write_all_vectored(f, &mut slices())
            }
            r => r,
        }?;
        self.written += total as u64;
        self.chunks.clear();
        Ok(())
    }
}

/// `Write::write_all_vectored` (unstable in std): write every slice, in order.
fn write_all_vectored(f: &mut File, mut slices: &mut [IoSlice<'_>]) -> io::Result<()> {
    IoSlice::advance_slices(&mut slices, 0);
    while !slices.is_empty() {
        match f.write_vectored(slices) {
            Ok(0) => return Err(io::Error::new(io::ErrorKind::WriteZero, "failed to write whole buffer")),
            Ok(n) => IoSlice::advance_slices(&mut slices, n),
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

impl Write for Sink {
    fn write(&mut self, mut data: &[u8]) -> io::Result<usize> {
        let n = data.len();
        while !data.is_empty() {
            if self.last == CHUNK {
                if self.chunks.len() == MAX_HELD {
                    self.put(CHUNK)?;
                }
                self.chunks.push(Chunk::take());
                self.last = 0;
            }
            let take = (CHUNK - self.last).min(data.len());
            let at = self.last;
            if let Some(c) = self.chunks.last_mut() {
                c.bytes_mut()[at..at + take].copy_from_slice(&data[..take]);
            }
            self.last += take;
            data = &data[take..];
        }
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Create `path` for direct writes where the file system allows it; `true` when it does.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn open(path: &Path) -> io::Result<(File, bool)> {
    use std::os::unix::fs::OpenOptionsExt;
    let mut o = std::fs::OpenOptions::new();
    o.write(true).create(true).truncate(true);
    #[cfg(test)]
    if REFUSE_DIRECT.load(std::sync::atomic::Ordering::Relaxed) {
        return Ok((o.open(path)?, false));
    }
    // A refusal is EINVAL on most file systems; whatever it is, the plain open says whether the
    // file can be made at all.
    match o.clone().custom_flags(libc::O_DIRECT).open(path) {
        Ok(f) => Ok((f, true)),
        Err(_) => Ok((o.open(path)?, false)),
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn open(path: &Path) -> io::Result<(File, bool)> {
    Ok((File::create(path)?, false))
}

/// Clear `O_DIRECT` on an open file.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn buffered(f: &File) -> io::Result<()> {
    use std::os::fd::AsRawFd;
    let fd = f.as_raw_fd();
    // SAFETY: fcntl on a descriptor this `File` owns; F_GETFL/F_SETFL read and set status flags.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    // SAFETY: as above.
    if flags < 0 || unsafe { libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_DIRECT) } < 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn buffered(_: &File) -> io::Result<()> {
    Ok(())
}
