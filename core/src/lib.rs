//! inkstep-core: everything in inkstep that is not a register access.
//!
//! `no_std` and allocation-free so that the firmware, the simulator and the host tests
//! all run this one copy of the logic. docs/architecture.md shows the data flow through
//! the modules and the firmware's tasks. Modules are grouped by responsibility:
//! - the motion contract between move producers and the planner: [`motion`]
//! - exact interpolation in integer step space: [`interpolation`]
//! - look-ahead planning, junctions and velocity profiles: [`planner`]
//! - step generation (segment preparation, the step queue, the step interrupt's work,
//!   the output configuration): [`stepper`]
//! - the one task-to-interrupt ring (the USB byte stream, and under the step queue): [`ring`]
//! - libm-free f32 math (sine, cosine, arctangent, square root): [`fmath`]
//! - decimal text without `core::fmt` (replies, listings): [`decimal`]; the stores'
//!   checksum: [`crc`]
//! - machine settings (the `$n` table, checks, byte image) and their flash store:
//!   [`settings`], [`settings_store`]
//! - G-code parsing and interpretation: [`gcode`]
//! - machine state, alarms and safety inputs, homing, the planner interface: [`machine`]
//! - the Grbl 1.1 serial protocol: [`protocol`]
//! - standalone use: [`keypad`] (scan and debounce), [`hmi`] (menus and drawing modes),
//!   [`screens`] (LCD pages, framebuffer and ST7920 flush)
//! - the shell logic the firmware and the simulator share (boot, the protocol tick,
//!   keypad scans, the LCD's view, what to save and when): [`controller`], and the
//!   motion pipeline behind the machine's motion trait: [`pipeline`]
//! - construction of those large structs in their final place: [`in_place`] (its
//!   [`init_fields!`] macro)
//! - what work each layer still holds, combined where the service loop sleeps: [`pending`]
//!
//! Floating point is allowed in planning code (tasks), never in the step interrupt path.
#![cfg_attr(not(test), no_std)]
// Denied, not forbidden: the in-place constructors (`init_in` of the controller,
// protocol, machine, pipeline and planner, and `in_place::build`) allow it locally to
// build the firmware's static cells field by field instead of on init's stack.
#![deny(unsafe_code)]
#![deny(clippy::undocumented_unsafe_blocks)]

pub mod controller;
pub mod crc;
pub mod decimal;
pub mod fmath;
pub mod gcode;
pub mod halt;
pub mod hmi;
pub mod in_place;
pub mod interpolation;
pub mod keypad;
pub mod machine;
pub mod motion;
pub mod pending;
pub mod pipeline;
pub mod planner;
pub mod protocol;
pub mod ring;
pub mod screens;
pub mod settings;
pub mod settings_store;
pub mod stepper;
