//! The inkstep firmware library: the board support that the RTIC app (`main.rs`) and
//! the on-target tests (`tests/on_target.rs`) share. All logic lives in `inkstep-core`.
#![no_std]
// Every unsafe block says why it is sound (a `SAFETY:` comment).
#![deny(clippy::undocumented_unsafe_blocks)]

pub mod board;
pub mod fault;
pub mod service_tick;
pub mod steps;
