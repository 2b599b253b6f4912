//! inkstep-core: everything in inkstep that is not a register access.
//!
//! `no_std` and allocation-free so that the firmware, the simulator and the host tests
//! all run this one copy of the logic. Modules are grouped by responsibility:
//! - the motion contract between move producers and the planner: [`motion`]
//! - exact interpolation in integer step space: [`interp`]
//! - look-ahead planning, junctions and velocity profiles: [`planner`]
//! - step generation (segment preparation, the step interrupt's work): [`stepper`]
//! - measurement of step traces against an ideal path: [`analysis`]
//! - the benchmark programs' G-code subset: [`refprog`]
//! - compact sine/cosine/arctangent for planning code: [`trig`]
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
