//! inkstep-sim: the firmware core on a PC, in virtual time.
//!
//! The simulator is wiring only: it feeds bytes, keys and timer interrupts to the same
//! `inkstep-core` code the firmware runs, and records what comes out (responses, step
//! events, LCD frames). Everything that decides anything lives in the core.

pub mod analysis;
pub mod bench;
pub mod board;
pub mod demo;
pub mod flash;
pub mod grbl_model;
pub mod keys;
pub mod kinematics;
pub mod latency;
pub mod lcd;
pub mod paths;
pub mod plot;
pub mod profiles;
pub mod render;
pub mod run;
pub mod serve;
pub mod trace;
