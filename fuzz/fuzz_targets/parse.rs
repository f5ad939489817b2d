//! Fuzz the front end: any bytes through parse, check and format must not panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let mut sources = rocc::source::SourceMap::default();
    let _ = rocc::check::check_text("fuzz.scn", text, std::path::Path::new("."), &mut sources);
    if let Ok(out) = rocc::syntax::format_source(text) {
        assert_eq!(rocc::syntax::format_source(&out).ok().as_deref(), Some(out.as_str()));
    }
});
