//! Road pass. In: the checked `Road` (template + parameters). Out: a `Map` in the world frame.

pub mod map;

pub use map::Map;
