//! rocc: a compiler from declarative driving-scenario files (`.scn`) to the sensor data that
//! perception and planning stacks train on. See ARCHITECTURE.md for the passes.

pub mod backend;
pub mod check;
pub mod ciren;
pub mod compile;
pub mod diag;
pub mod edit;
pub mod eval;
pub mod expect;
pub mod fsio;
pub mod geom;
pub mod grammar;
pub mod import;
pub mod learn;
pub mod lidar;
pub mod llm;
pub mod output;
pub mod place;
pub mod raster;
pub mod road;
pub mod rollout;
pub mod sample;
pub mod source;
pub mod syntax;
pub mod view;
pub mod visibility;
