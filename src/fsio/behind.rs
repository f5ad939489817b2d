//! Writes that finish behind the caller. A clip's frame writes its large files (occupancy, LiDAR)
//! through a `Behind`: the bytes are gathered in memory (`Sink`), and one writer thread puts them
//! on the disk and renames them into place while the frame's thread computes the next frame.
//! Direct writes wait for the disk (`sink.rs`); done in the frame's thread, that wait left a core
//! idle about a sixth of the time at 0.2 deg (`bench e2e`). `finish` waits for every file and
//! returns the first failure, so a clip writes its manifest only once all its files are in place;
//! a `Behind` dropped without `finish` still waits, so no write outlives its clip.

use super::Sink;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Sender, channel};
use std::sync::{Arc, Condvar, Mutex, OnceLock};

/// Bytes queued for the writer thread at most; a caller beyond it waits (the disk sets the pace).
const MAX_QUEUED: u64 = 48 << 20;

struct Job {
    sink: Sink,
    path: PathBuf,
    tally: Arc<Tally>,
}

#[derive(Default)]
struct Tally {
    state: Mutex<State>,
    changed: Condvar,
}

#[derive(Default)]
struct State {
    pending: usize,
    error: Option<io::Error>,
}

/// Bytes queued across every `Behind`, and its condition.
static QUEUED: (Mutex<u64>, Condvar) = (Mutex::new(0), Condvar::new());

fn writer() -> Option<&'static Mutex<Sender<Job>>> {
    static TX: OnceLock<Option<Mutex<Sender<Job>>>> = OnceLock::new();
    TX.get_or_init(|| {
        let (tx, rx) = channel::<Job>();
        let spawned = std::thread::Builder::new().name("rocc-writer".into()).spawn(move || {
            for job in rx {
                run(job);
            }
        });
        spawned.ok().map(|_| Mutex::new(tx))
    })
    .as_ref()
}

fn run(job: Job) {
    let Job { sink, path, tally } = job;
    let (size, tmp) = (sink.len(), sink.tmp().to_path_buf());
    // A panic here would leave `finish` waiting forever: it becomes this file's error.
    let write = std::panic::AssertUnwindSafe(|| super::settle(sink, &path));
    let result = std::panic::catch_unwind(write).unwrap_or_else(|_| {
        let _ = std::fs::remove_file(&tmp);
        Err(io::Error::other("the writer thread failed"))
    });
    {
        let (lock, cv) = &QUEUED;
        if let Ok(mut q) = lock.lock() {
            *q = q.saturating_sub(size);
        }
        cv.notify_all();
    }
    if let Ok(mut s) = tally.state.lock() {
        s.pending -= 1;
        if let Err(e) = result
            && s.error.is_none()
        {
            s.error = Some(io::Error::new(e.kind(), format!("{}: {e}", path.display())));
        }
    }
    tally.changed.notify_all();
}

/// A set of files written behind the caller; see the module's header.
#[derive(Default)]
pub struct Behind {
    tally: Arc<Tally>,
}

impl Behind {
    pub fn new() -> Self {
        Self::default()
    }

    /// `write_atomic`, except that the file reaches its final name later (by `finish`). Returns
    /// the file's size. Errors of `fill` come back here; errors of the disk from `finish`.
    pub fn write_atomic(&self, path: &Path, fill: impl FnOnce(&mut Sink) -> io::Result<()>) -> io::Result<u64> {
        let sink = super::filled(path, fill)?;
        let size = sink.len();
        let Some(tx) = writer() else {
            // No thread to be had: write it here.
            return super::settle(sink, path);
        };
        {
            let (lock, cv) = &QUEUED;
            let mut q = lock.lock().map_err(|_| io::Error::other("write queue poisoned"))?;
            while *q > 0 && *q + size > MAX_QUEUED {
                q = cv.wait(q).map_err(|_| io::Error::other("write queue poisoned"))?;
            }
            *q += size;
        }
        if let Ok(mut s) = self.tally.state.lock() {
            s.pending += 1;
        }
        let job = Job { sink, path: path.to_path_buf(), tally: self.tally.clone() };
        let sent = tx.lock().map_err(|_| io::Error::other("write queue poisoned"))?.send(job);
        if let Err(back) = sent {
            // The writer thread is gone (it never is while the process runs): write it here.
            run(back.0);
        }
        Ok(size)
    }

    /// Wait for every file written through `self`; the first failure, with its path.
    pub fn finish(self) -> io::Result<()> {
        self.wait().map_or(Ok(()), Err)
    }

    fn wait(&self) -> Option<io::Error> {
        let mut s = self.tally.state.lock().ok()?;
        while s.pending > 0 {
            s = self.tally.changed.wait(s).ok()?;
        }
        s.error.take()
    }
}

impl Drop for Behind {
    fn drop(&mut self) {
        let _ = self.wait();
    }
}
