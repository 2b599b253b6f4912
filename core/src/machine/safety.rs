//! The safety side of the machine: its alarms (Grbl's numbers) and the levels of its
//! safety and control inputs (e-stop, limit switches, feed hold, cycle start).

use crate::motion::AXES;

/// Alarms, with Grbl's numbers (10 is inkstep's e-stop, as grblHAL numbers it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Alarm {
    HardLimit = 1,
    SoftLimit = 2,
    AbortCycle = 3,
    HomingFailReset = 6,
    HomingFailDoor = 7,
    HomingFailPullOff = 8,
    HomingFailApproach = 9,
    EStop = 10,
}

impl Alarm {
    pub fn code(self) -> u8 {
        self as u8
    }
    /// Critical alarms need a soft reset before `$X`/`$H` (position may be lost).
    pub(super) fn critical(self) -> bool {
        matches!(self, Alarm::HardLimit | Alarm::EStop)
    }
}

/// Input levels, already corrected for inversion (true = active).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    pub estop: bool,
    /// Limit/home switch per axis.
    pub limits: [bool; AXES],
    /// The SYNC / feed-hold input: pause while active.
    pub feed_hold: bool,
    pub cycle_start: bool,
}
