//! inkstep-host: the PC side of inkstep. The binary (main.rs) is only the
//! command line; everything it does lives in these modules so tests and the
//! benchmark reach it directly.

pub mod arcs;
pub mod bench;
pub mod biarc;
pub mod estimate;
pub mod font;
pub mod gcode_out;
pub mod geom;
pub mod hatch;
pub mod plan;
pub mod preview;
pub mod resume;
pub mod stream;
pub mod svg_bench;
pub mod svg_in;
pub mod text;
pub mod toolpath;
pub mod web;
