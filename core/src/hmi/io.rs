//! The HMI's contract with the integrator: what it is told about the machine
//! ([`Config`], [`Snapshot`]) and what it asks for ([`Action`]). Kept apart from the state
//! machine so the firmware and the simulator can read it on its own: these types are
//! all they need to wire the HMI in.

use heapless::Vec;

use crate::motion::{Move, StepPos};

/// Machine parameters the HMI needs (the integrator copies them from the settings).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Steps per mm of X, Y and Z (the pen axis).
    pub steps_per_mm: [f32; 3],
    /// Pen axis position (mm) with the pen lifted / on the paper.
    pub pen_up_mm: f32,
    pub pen_down_mm: f32,
    /// Path speed of the drawing modes.
    pub draw_feed_mm_min: f32,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            steps_per_mm: [80.0, 80.0, 100.0],
            pen_up_mm: 5.0,
            pen_down_mm: 0.0,
            draw_feed_mm_min: 600.0,
        }
    }
}

/// The machine state as the HMI needs it (Grbl's states, simplified).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MachineState {
    Idle,
    Run,
    Hold,
    Jog,
    Homing,
    /// Alarm with Grbl's alarm code.
    Alarm(u8),
}

impl MachineState {
    pub fn name(self) -> &'static str {
        match self {
            MachineState::Idle => "Idle",
            MachineState::Run => "Run",
            MachineState::Hold => "Hold",
            MachineState::Jog => "Jog",
            MachineState::Homing => "Home",
            MachineState::Alarm(_) => "Alarm",
        }
    }

    /// Whether the axes are (or may be) moving.
    pub fn moving(self) -> bool {
        matches!(
            self,
            MachineState::Run | MachineState::Jog | MachineState::Homing
        )
    }
}

/// A snapshot of the machine, passed with every call.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Snapshot {
    pub state: MachineState,
    /// Position in steps, in the planner's coordinates (what Move targets use).
    pub pos: StepPos,
    /// Current path speed.
    pub feed_mm_min: f32,
    /// No move is queued or executing.
    pub queue_empty: bool,
    /// Direction of the latest step on X and Y (-1, 0, +1).
    pub dir: [i8; 2],
}

impl Snapshot {
    /// An idle machine at `pos` with nothing queued.
    pub fn idle_at(pos: StepPos) -> Self {
        Snapshot {
            state: MachineState::Idle,
            pos,
            feed_mm_min: 0.0,
            queue_empty: true,
            dir: [0, 0],
        }
    }
}

/// Buzzer patterns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Beep {
    /// A job finished.
    Done,
    /// Refused input or a job that stopped early.
    Error,
    /// An alarm was raised.
    Alarm,
}

impl Beep {
    /// The buzzer pattern: alternating on and off times in ms, starting with on.
    /// Distinct by ear: one short chirp, two quick beeps, three long ones.
    pub fn pattern(self) -> &'static [u16] {
        match self {
            Beep::Done => &[150],
            Beep::Error => &[80, 80, 80],
            Beep::Alarm => &[300, 150, 300, 150, 300],
        }
    }
}

/// What the integrator must do, in the order given.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Action {
    /// Append a move to the planner queue.
    Queue(Move),
    /// Start (or retarget) continuous jogging in `dir` (signs of X, Y) at this speed.
    JogStart {
        dir: [i8; 2],
        feed_mm_min: f32,
    },
    /// Stop jogging (decelerate, then flush the jog).
    JogStop,
    /// Feed hold (decelerate to a stop, keep the queue).
    FeedHold,
    /// Resume after a feed hold.
    Resume,
    /// Feed hold, wait until stopped, then clear the queue; the position stays known.
    Abort,
    /// Run the homing cycle.
    Home,
    /// Make the current position the origin (0, 0).
    SetOrigin,
    /// Clear an alarm (like Grbl's `$X`).
    Unlock,
    Beep(Beep),
}

/// The actions of one call (a job start is the largest: up to 8 moves).
pub type Actions = Vec<Action, 10>;

/// The Grbl alarm texts shown on the alarm page.
pub fn alarm_text(code: u8) -> &'static str {
    match code {
        1 => "Hard limit",
        2 => "Soft limit",
        3 => "Reset in motion",
        4 | 5 => "Probe fail",
        6 => "Homing: reset",
        7 => "Homing: door",
        8 => "Homing: pull-off",
        9 => "Homing: no switch",
        10 => "Emergency stop",
        _ => "Alarm",
    }
}
