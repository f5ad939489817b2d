//! Scene text through the checker and the front (sample to rollout), panicking with the
//! diagnostics' messages: shared by the tests that read tracks of `.scn` text.
#![allow(dead_code)] // each test crate uses part of it

pub fn front_of(text: &str) -> rocc::compile::Front {
    let mut sources = rocc::source::SourceMap::default();
    let s = rocc::check::check_text("t.scn", text, std::path::Path::new("."), &mut sources)
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| d.message.clone()).collect::<Vec<_>>()));
    rocc::compile::front(s, None)
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| d.message.clone()).collect::<Vec<_>>()))
}
