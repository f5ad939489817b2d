//! GPU failures as diagnostics. burn's GPU backends report a missing adapter, an exhausted
//! device memory or a buffer beyond the device's limits by panicking (cubecl's `IoError` turned
//! into a panic on a failed read or allocation). `guarded` runs device work under
//! `catch_unwind` with the panic message kept off stderr, and `classify` turns the message into
//! E0910-E0913 with what to change.

use crate::diag::Diagnostic;
use std::cell::Cell;
use std::panic::{AssertUnwindSafe, PanicHookInfo, catch_unwind};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, Once};

thread_local! {
    /// Set while this thread runs a guarded call: its panics are caught, so not printed.
    static GUARDED: Cell<bool> = const { Cell::new(false) };
}

/// Guarded calls running on any thread.
static ACTIVE: AtomicUsize = AtomicUsize::new(0);
/// Messages of panics silenced on the device's own threads, for `classify`: the caller's panic
/// may only say that the device thread failed.
static DEVICE_PANICS: Mutex<Vec<String>> = Mutex::new(Vec::new());
static HOOK: Once = Once::new();

/// cubecl runs each device's work on a thread of its own, named `DS<stage>-<type>-<index>`
/// (cubecl-common's device channel), and forwards that thread's panic to the caller.
fn on_device_thread() -> bool {
    std::thread::current().name().is_some_and(|n| n.starts_with("DS"))
}

/// A hook in front of the previous one, installed once: panics of guarded work are recorded
/// instead of printed; every other panic prints as before.
fn install_hook() {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info: &PanicHookInfo| {
            let silenced = GUARDED.with(Cell::get) || (ACTIVE.load(Ordering::SeqCst) > 0 && on_device_thread());
            if !silenced {
                previous(info);
                return;
            }
            if let Ok(mut v) = DEVICE_PANICS.lock()
                && v.len() < 16
            {
                v.push(info.payload_as_str().unwrap_or("").to_string());
            }
        }));
    });
}

/// Run device work; a panic inside becomes the diagnostic `classify` gives its message.
pub fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, Diagnostic> {
    install_hook();
    let was = GUARDED.with(|g| g.replace(true));
    ACTIVE.fetch_add(1, Ordering::SeqCst);
    let out = catch_unwind(AssertUnwindSafe(f));
    ACTIVE.fetch_sub(1, Ordering::SeqCst);
    GUARDED.with(|g| g.set(was));
    let recorded = DEVICE_PANICS.lock().map(|mut v| std::mem::take(&mut *v)).unwrap_or_default();
    out.map_err(|payload| {
        let own = payload
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        let mut all = recorded;
        all.push(own);
        classify(&all.join("\n"))
    })
}

/// What a device failure's message means. The message is searched case-insensitively for what
/// wgpu, cubecl and the CUDA driver say; the first line of the most telling part is quoted.
pub fn classify(message: &str) -> Diagnostic {
    let lower = message.to_ascii_lowercase();
    let has = |needles: &[&str]| needles.iter().any(|n| lower.contains(n));
    let quoted = quote(message);
    let smaller = "lower `--grounded-batch` (compile) or the config's `batch` or `train.crop` (train)";
    if has(&["can't allocate buffer", "buffertoobig", "max_buffer_size", "max_storage_buffer_binding_size"])
        || (lower.contains("buffer") && has(&["exceeds", "limit"]))
    {
        Diagnostic::error("E0912", format!("a buffer is beyond the device's limits: {quoted}"))
            .help(format!("{smaller}, or use another device (`--device cuda` or `--device cpu`)"))
    } else if has(&["out of memory", "out of device memory", "outofmemory", "out_of_memory", "page size"]) {
        Diagnostic::error("E0911", format!("the device ran out of memory: {quoted}"))
            .help(format!("{smaller}, free the GPU of other work, or use another device"))
    } else if has(&[
        "adapter",
        "unable to acquire wgpu device",
        "unable to initialize wgpu",
        "no device",
        "no_device",
        "driver",
        "cuinit",
        "libcuda",
        "vulkan",
        "service initialization failed",
    ]) {
        Diagnostic::error("E0910", format!("no usable GPU device: {quoted}"))
            .help("check the GPU driver (`vulkaninfo`, `nvidia-smi`), or use `--device cpu`")
    } else {
        Diagnostic::error("E0913", format!("the device failed: {quoted}"))
            .help("rerun with `--device cpu` to check the model and weights; `rocc explain E0913` tells more")
    }
}

/// The first non-empty line (the device thread's own message where one was recorded, which
/// comes first), cut to a readable length.
fn quote(message: &str) -> String {
    let line = message.lines().map(str::trim).find(|l| !l.is_empty()).unwrap_or("no message");
    let mut s: String = line.chars().take(240).collect();
    if s.len() < line.len() {
        s.push_str("...");
    }
    format!("`{s}`")
}
