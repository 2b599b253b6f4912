//! inkstep-core: everything in inkstep that is not a register access.
//!
//! `no_std` and allocation-free so that the firmware, the simulator and the host tests
//! all run this one copy of the logic. Modules are grouped by responsibility:
//! - geometry and the motion contract: [`motion`]
//!
//! Floating point is allowed in planning code (tasks), never in the step interrupt path.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]

pub mod analysis;
pub mod interp;
pub mod motion;
pub mod planner;
pub mod refprog;
pub mod stepper;
pub mod trig;
