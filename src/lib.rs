//! rocc: a compiler from declarative driving-scenario files (`.scn`) to the sensor data that
//! perception and planning stacks train on. See ARCHITECTURE.md for the passes.

pub mod check;
pub mod diag;
pub mod geom;
pub mod place;
pub mod road;
pub mod sample;
pub mod source;
pub mod syntax;
