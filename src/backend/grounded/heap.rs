//! Keeps freed memory in the process during training on the CPU. A `cpu-small` step allocates
//! and frees tensors of tens of megabytes (the crop's logits, their gradients, the BEV); glibc
//! serves blocks that large with a fresh `mmap` and returns them with `munmap`, so every step
//! would fault in and zero hundreds of megabytes of pages, about a third of its CPU time in the
//! kernel (`perf record` on `bench train`). Served from the heap and never trimmed, the pages
//! are reused from the second step on. Values do not change (only where the bytes live).

/// Serve every allocation from the heap and keep its top when freed. Process-wide, once; a
/// no-op off glibc.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            // SAFETY: mallopt only changes glibc's allocation policy; blocks already handed out
            // (mmapped or not) are freed as they were allocated.
            unsafe {
                libc::mallopt(libc::M_MMAP_MAX, 0);
                libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
            }
        });
    }
}
