//! Machine control: the [`MotionControl`] trait that the planner implements, the
//! commands queued through it, the machine state ([`state`]: idle, run, hold, jog,
//! homing, alarm, check mode and their rules), its alarms and safety inputs
//! ([`safety`]), and the homing cycle ([`homing`]).
//!
//! The trait is deliberately small so that the G-code interpreter, the protocol and the
//! keypad modes all drive the same planner the same way, and so that tests can use a
//! fake planner. Everything the planner needs to know about a block travels in a
//! [`Command`].

pub mod homing;
pub mod safety;
pub mod state;
mod tell;

use crate::motion::{Command, StepPos};

pub use safety::{Alarm, InputPolarity, Inputs, PinLevels};
pub use state::{Machine, RunState, Taken};

/// What the motion is doing: the one answer to "is it running, holding, held?" that
/// the machine's state, its reports and the keypad ask of [`MotionControl::motion`]
/// (the pipeline works it out from its preparation and its step queue; nobody keeps
/// a copy). Whether commands are still queued is [`MotionControl::queued`]: a held
/// machine may have none, an idle one may have some not started yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MotionState {
    /// At rest and not held.
    Idle,
    /// Steps, a pen move or a wait are under way.
    Running,
    /// A G4 dwell runs and nothing is queued behind it (reported Idle, as Grbl does).
    Dwelling,
    /// A hold is bringing the machine to rest (braking, a pen move or a hold's Z-pen
    /// trip still under way).
    Holding,
    /// A hold keeps the machine at rest until resume.
    Held,
}

/// The planner queue has no room for another command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QueueFull;

/// What the machine state needs from the planner and step engine.
///
/// Semantics the implementation must keep:
/// - `push` appends to the look-ahead queue and starts motion unless held.
/// - `hold` decelerates to rest along the path and keeps the queue; `resume` continues
///   it from the exact position reached. [`MotionState`] is `Holding` or `Held` from `hold` until
///   `resume` or `clear`, and `Held` once the axes are at rest.
/// - `clear` stops at once (no further step), empties the queue and ends any hold;
///   `position` afterwards is the exact step count reached.
/// - `set_position` is only called at rest with an empty queue (homing, `G92` does
///   not use it: offsets live in the interpreter).
pub trait MotionControl {
    /// Queue one command.
    fn push(&mut self, cmd: Command) -> Result<(), QueueFull>;
    /// Commands queued and not yet finished (the one executing counts).
    fn queued(&self) -> usize;
    /// Queue size; `capacity() - queued()` is the free room (`Bf:` reports it).
    fn capacity(&self) -> usize;
    /// Decelerate to a stop, keep the queue.
    fn hold(&mut self);
    /// Continue after a hold.
    fn resume(&mut self);
    /// What the motion is doing now.
    fn motion(&self) -> MotionState;
    /// A hold is in effect (decelerating or at rest).
    fn is_holding(&self) -> bool {
        matches!(self.motion(), MotionState::Holding | MotionState::Held)
    }
    /// Steps are being produced (including a dwell or pen lift in progress).
    fn is_moving(&self) -> bool {
        matches!(
            self.motion(),
            MotionState::Running | MotionState::Dwelling | MotionState::Holding
        )
    }
    /// Stop immediately and drop everything queued.
    fn clear(&mut self);
    /// Feed override (10-200 %) and rapid override (25, 50 or 100 %).
    fn set_overrides(&mut self, feed_percent: u8, rapid_percent: u8);
    /// Current machine position in steps.
    fn position(&self) -> StepPos;
    /// Redefine the current position (at rest, queue empty).
    fn set_position(&mut self, pos: StepPos);
    /// Current path speed in mm/min (for `FS:`).
    fn speed(&self) -> f32;
    /// New settings (`$n=v`, `$RST`), given at rest, before the next line runs: the
    /// limits must apply to every move queued after the change, and nothing queued
    /// may be lost. Fakes that plan nothing may keep the default.
    fn configure(&mut self, _settings: &crate::settings::Settings) {}
    /// The servo pen's level now (0 = up .. `motion::PEN_FULL` = down), as far as the
    /// queue has run, lifted while a hold keeps XY at rest: what the pen servo output
    /// shows. Fakes without a servo pen may keep the default.
    fn pen_level(&self) -> u16 {
        0
    }
    /// The servo pen touches the paper ([`MotionControl::pen_level`] above 0).
    fn pen_down(&self) -> bool {
        self.pen_level() > 0
    }

    /// The N number of the line whose motion is running (0 or `None`: no number).
    /// Fakes may keep the default.
    fn line(&self) -> Option<u32> {
        None
    }

    /// What runs is a G4 dwell and nothing is queued behind it (the state is then
    /// reported as Idle, as Grbl does).
    fn dwelling(&self) -> bool {
        self.motion() == MotionState::Dwelling
    }

    /// Nothing queued and at rest.
    fn is_idle(&self) -> bool {
        self.queued() == 0 && !self.is_moving()
    }
    /// Free queue entries.
    fn free(&self) -> usize {
        self.capacity().saturating_sub(self.queued())
    }
}
