//! A test's own temporary directory, removed when its guard is dropped, whether the test passes
//! or panics: test runs leave nothing behind in the system's temporary directory.
#![allow(dead_code)] // each test crate uses part of it

use std::path::{Path, PathBuf};

pub struct TempDir(PathBuf);

impl TempDir {
    /// An empty directory `PREFIX-PID-NAME` under the system's temporary directory.
    pub fn new(prefix: &str, name: &str) -> TempDir {
        let d = std::env::temp_dir().join(format!("{prefix}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("temp dir");
        TempDir(d)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
