//! The inkstep firmware library: the board support that the RTIC app (`main.rs`) and
//! the on-target tests (`tests/on_target.rs`) share. All logic lives in `inkstep-core`.
#![no_std]

pub mod board;
pub mod fault;
pub mod steps;
