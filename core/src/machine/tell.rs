//! What the machine tells the people using it, as data: the [`RunState`] of its
//! status reports, the [`Event`]s the protocol prints for the host, the `(MSG, ...)`
//! text and the [`Prompt`] the LCD shows. The machine never formats text; these
//! types are its side of that boundary.

use super::safety::Alarm;

/// The state shown in status reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RunState {
    Idle,
    Run,
    /// `complete`: at rest (Hold:0); otherwise still decelerating (Hold:1).
    Hold {
        complete: bool,
    },
    Jog,
    /// Safety door (0x84): `at_rest` false while stopping (Door:2), true once stopped
    /// and ready to resume with cycle start (Door:0; there is no door switch to hold
    /// it open).
    Door {
        at_rest: bool,
    },
    Alarm,
    Home,
    Check,
    /// `$SLP`: the motors are released and only a reset wakes the machine.
    Sleep,
}

/// Something the protocol should tell the host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    Alarm(Alarm),
    /// `[MSG:...]` text.
    Msg(&'static str),
    /// `[MSG:Job started]`.
    JobStarted,
    /// `[MSG:Pen change: pen N, cycle start to continue]`.
    PenChange(u8),
    /// `[MSG:Job finished ...]` with the job's duration.
    JobFinished {
        ms: u32,
        moves: u32,
    },
}

/// The longest `(MSG, ...)` text kept for the LCD (the sender gets all of it).
pub const MESSAGE_LEN: usize = 40;
/// A message's text.
pub type Message = heapless::Vec<u8, MESSAGE_LEN>;

/// What the machine waits for the user to do: the LCD's prompt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Prompt {
    /// M0: paused until cycle start.
    Paused,
    /// M6 T`n`: put pen `n` in, then cycle start.
    PenChange(u8),
}
