//! The step outputs' configuration, derived from the settings in one place for the
//! board and the simulator alike: pin polarities, output mode, pulse width, the
//! reversal guard, the driver-enable polarity and whether limit switches stop stepping
//! at once. The shell applies it at boot and whenever the settings change.

use super::TIMER_HZ;
use crate::settings::{OutputMode, Settings};

/// Direction hold time after a step pulse ends, before a reversal turns the pin: 1 us,
/// above every common driver's requirement (A4988 200 ns, DRV8825 650 ns, TB6600-style
/// opto inputs ~1 us with their set-up time counted in the rest of the wait).
pub const DIR_HOLD_COUNTS: u32 = TIMER_HZ / 1_000_000;

/// The longest step pulse in timer counts: the board's 16-bit compare register.
const MAX_PULSE_COUNTS: u32 = 0xFFFF;

/// How the step outputs behave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OutputConfig {
    /// Step pins whose idle level is high ($2; bit i = axis i).
    pub step_invert: u8,
    /// Direction pins whose meaning is swapped ($3).
    pub dir_invert: u8,
    /// 4-phase half-step coils instead of step/dir ($200).
    pub four_phase: bool,
    /// Step pulse width in timer counts ($0), 1..=0xFFFF.
    pub pulse_ticks: u32,
    /// The driver enable pin is active low ($4 = 0, A4988/DRV8825 /EN).
    pub enable_active_low: bool,
    /// Axes whose limit switch stops stepping at once, like the e-stop: those with a
    /// switch ($214) when hard limits are on ($21), else none.
    pub hard_limit_axes: u8,
}

impl OutputConfig {
    /// Length of the reversal guard: a command that reverses an axis whose pulse is
    /// high first waits this long (pulse width plus hold time) before the direction pin
    /// turns (see [`super::exec::Executor::set_turn_guard`]). 4-phase outputs are
    /// levels: nothing to guard, 0.
    pub fn turn_guard_ticks(&self) -> u32 {
        if self.four_phase {
            0
        } else {
            self.pulse_ticks + DIR_HOLD_COUNTS
        }
    }
}

impl From<&Settings> for OutputConfig {
    fn from(s: &Settings) -> Self {
        let pulse = u32::from(s.step_pulse_us()) * (TIMER_HZ / 1_000_000);
        OutputConfig {
            step_invert: s.step_invert_mask() & 0b111,
            dir_invert: s.dir_invert_mask() & 0b111,
            four_phase: s.output_mode() == OutputMode::FourPhase,
            pulse_ticks: pulse.clamp(1, MAX_PULSE_COUNTS),
            enable_active_low: !s.invert_enable(),
            hard_limit_axes: if s.hard_limits() {
                s.switch_mask() & 0b111
            } else {
                0
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_each_setting_reach_the_configuration() {
        let mut s = Settings::default();
        let c = OutputConfig::from(&s);
        assert_eq!(
            c,
            OutputConfig {
                step_invert: 0,
                dir_invert: 0,
                four_phase: false,
                pulse_ticks: 720, // $0=10 us at 72 MHz
                enable_active_low: true,
                hard_limit_axes: 0,
            }
        );
        assert_eq!(c.turn_guard_ticks(), 720 + 72);
        s.set(0, 255.0).unwrap();
        s.set(2, 5.0).unwrap();
        s.set(3, 6.0).unwrap();
        s.set(4, 1.0).unwrap();
        s.set(21, 1.0).unwrap();
        s.set(200, 1.0).unwrap();
        let c = OutputConfig::from(&s);
        assert_eq!(
            c.pulse_ticks,
            255 * 72,
            "the longest pulse still fits the 16-bit compare"
        );
        assert_eq!((c.step_invert, c.dir_invert), (5, 6));
        assert!(c.four_phase && !c.enable_active_low);
        assert_eq!(c.hard_limit_axes, 3, "$21 arms the $214 axes");
        s.set(214, 2.0).unwrap();
        assert_eq!(OutputConfig::from(&s).hard_limit_axes, 2);
        assert_eq!(c.turn_guard_ticks(), 0, "coils are levels");
    }
}
