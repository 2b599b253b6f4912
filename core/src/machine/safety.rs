//! The safety side of the machine: its alarms (Grbl's numbers) and its safety and
//! control inputs (e-stop, limit switches, feed hold, cycle start): the pins' levels
//! as the shell reads them, and what they mean with the settings' polarities.

use crate::motion::AXES;
use crate::settings::Settings;

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

/// The safety and control inputs' electrical levels as the pins read them (true =
/// high), before any meaning: the shell (board or simulator) reads them, and
/// [`InputPolarity::decode`] says what they mean.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PinLevels {
    pub estop: bool,
    /// Limit/home switch per axis; `None` where the board has no pin for it.
    pub limits: [Option<bool>; AXES],
    pub feed_hold: bool,
    pub cycle_start: bool,
}

/// How pin levels map to active inputs, from the settings. Switches are wired normally
/// closed to ground with pull-ups, so by default an e-stop or a limit switch is active
/// when its pin reads high (the circuit is open, which a broken wire also gives), and
/// feed hold and cycle start (push buttons, the SYNC line) when theirs reads low. `$5`
/// inverts the limit pins; `$215` the e-stop, feed-hold and cycle-start pins.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InputPolarity {
    pub invert_limits: bool,
    pub invert_controls: bool,
}

impl From<&Settings> for InputPolarity {
    fn from(s: &Settings) -> Self {
        InputPolarity {
            invert_limits: s.invert_limits(),
            invert_controls: s.invert_inputs(),
        }
    }
}

impl InputPolarity {
    /// The inputs that `pins` make active.
    pub fn decode(self, pins: PinLevels) -> Inputs {
        // Each input is active when its level differs from its level at rest.
        let rest = |high_at_rest: bool| high_at_rest != self.invert_controls;
        Inputs {
            estop: pins.estop != rest(false),
            limits: pins
                .limits
                .map(|l| l.is_some_and(|high| high != self.invert_limits)),
            feed_hold: pins.feed_hold != rest(true),
            cycle_start: pins.cycle_start != rest(true),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every input at rest with the default wiring: switches closed (low), buttons
    /// released (high).
    const AT_REST: PinLevels = PinLevels {
        estop: false,
        limits: [Some(false), Some(false), None],
        feed_hold: true,
        cycle_start: true,
    };

    #[test]
    fn default_polarity_reads_open_switches_and_pressed_buttons_as_active() {
        let p = InputPolarity::from(&Settings::default());
        assert_eq!(p.decode(AT_REST), Inputs::default());
        let all = PinLevels {
            estop: true,
            limits: [Some(true), Some(true), None],
            feed_hold: false,
            cycle_start: false,
        };
        let i = p.decode(all);
        assert!(i.estop && i.feed_hold && i.cycle_start);
        assert_eq!(i.limits, [true, true, false], "no pin, never active");
    }

    #[test]
    fn setting_215_inverts_estop_feed_hold_and_cycle_start_and_5_the_limits() {
        let mut s = Settings::default();
        s.set(215, 1.0).unwrap();
        let p = InputPolarity::from(&s);
        let i = p.decode(AT_REST);
        assert!(i.estop, "e-stop inverted");
        assert!(i.feed_hold, "feed hold inverted");
        assert!(i.cycle_start, "cycle start inverted");
        assert_eq!(i.limits, [false; AXES], "$215 leaves the limits alone");
        s.set(215, 0.0).unwrap();
        s.set(5, 1.0).unwrap();
        let i = InputPolarity::from(&s).decode(AT_REST);
        assert_eq!(
            i.limits,
            [true, true, false],
            "$5 inverts the wired limits only"
        );
        assert!(!i.estop && !i.feed_hold && !i.cycle_start);
    }
}
