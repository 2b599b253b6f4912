//! What the board's status and power outputs show from one millisecond to the next:
//! the busy LED and busy output, the motors' power (`$1`, the step idle delay, and
//! `$SLP`), and the blink code of a board that refuses to run.
//!
//! Decided here, evaluated by the shell every millisecond whatever the protocol does
//! (the firmware's preparation task, which runs every tick; the protocol task sleeps
//! at idle, so nothing it alone decides can follow the end of a move). A pure
//! function of what the machine does and the time, with one memory: when it was last
//! busy.

/// The blink code of a board that refuses to run (a chip with too little flash):
/// three short flashes, then a pause, every [`BLINK_PERIOD_MS`].
pub const BLINK_PERIOD_MS: u32 = 2000;
const BLINK_ON_MS: u32 = 150;
const BLINK_STEP_MS: u32 = 400;
const BLINK_COUNT: u32 = 3;

/// `$1` at this value keeps the motors powered at rest.
pub const KEEP_POWERED: u8 = 255;

/// The machine as the outputs need it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Activity {
    /// Motion is under way or queued (a move, a jog, homing, a dwell or pen wait).
    pub busy: bool,
    /// Steps come or wait to come: the motors must be powered (anything queued,
    /// homing, a hold with moves left).
    pub needs_power: bool,
    /// The motors must be off whatever `$1` says (`$SLP`, a refused chip).
    pub released: bool,
    /// The board refuses to run: the LED shows the blink code instead of busy.
    pub refused: bool,
}

/// The outputs' levels (logical: the board applies polarities).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Levels {
    /// The busy LED is lit.
    pub led: bool,
    /// The busy output says busy.
    pub busy: bool,
    /// Drivers enabled / coils energised.
    pub motors: bool,
}

/// The memory of the outputs: how long ago the motors last needed power.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IdleOutputs {
    /// The last millisecond the motors needed power.
    last_needed_ms: u32,
    /// They have needed it since power-up (until then they are off, unless `$1` is
    /// 255).
    ever: bool,
}

impl IdleOutputs {
    pub const fn new() -> Self {
        IdleOutputs {
            last_needed_ms: 0,
            ever: false,
        }
    }

    /// The levels at `now_ms`, given what the machine does and `$1` (`idle_delay_ms`).
    /// Motors stay powered `idle_delay_ms` after the last millisecond they were needed
    /// (0: off at once at rest; 255: always, unless released).
    pub fn update(&mut self, a: Activity, idle_delay_ms: u8, now_ms: u32) -> Levels {
        if a.needs_power {
            self.last_needed_ms = now_ms;
            self.ever = true;
        }
        let held = idle_delay_ms == KEEP_POWERED
            || self.ever && now_ms.wrapping_sub(self.last_needed_ms) < u32::from(idle_delay_ms)
            || a.needs_power;
        let led = if a.refused { blink(now_ms) } else { a.busy };
        Levels {
            led,
            busy: a.busy && !a.refused,
            motors: held && !a.released,
        }
    }
}

/// The blink code's LED level at `now_ms`.
pub fn blink(now_ms: u32) -> bool {
    let t = now_ms % BLINK_PERIOD_MS;
    t < BLINK_COUNT * BLINK_STEP_MS && t % BLINK_STEP_MS < BLINK_ON_MS
}

#[cfg(test)]
mod tests {
    use super::*;

    const MOVING: Activity = Activity {
        busy: true,
        needs_power: true,
        released: false,
        refused: false,
    };
    const AT_REST: Activity = Activity {
        busy: false,
        needs_power: false,
        released: false,
        refused: false,
    };

    /// The first millisecond at which the motors are off, from `from`.
    fn off_at(o: &mut IdleOutputs, delay: u8, from: u32) -> Option<u32> {
        (from..from + 1000).find(|&t| !o.update(AT_REST, delay, t).motors)
    }

    #[test]
    fn motors_are_released_idle_delay_after_the_last_motion() {
        for delay in [0u8, 1, 25, 100, 254] {
            let mut o = IdleOutputs::new();
            for t in 0..50 {
                let l = o.update(MOVING, delay, t);
                assert!(l.motors && l.busy && l.led);
            }
            // The last millisecond with motion was 49.
            assert_eq!(
                off_at(&mut o, delay, 50),
                Some(49 + u32::from(delay).max(1)),
                "$1={delay}"
            );
        }
    }

    #[test]
    fn delay_255_keeps_them_powered_and_sleep_releases_them_anyway() {
        let mut o = IdleOutputs::new();
        assert!(!o.update(AT_REST, 25, 0).motors, "off from power-up");
        assert!(o.update(AT_REST, 255, 0).motors, "255: on from power-up");
        o.update(MOVING, 255, 0);
        assert_eq!(off_at(&mut o, 255, 1), None);
        let asleep = Activity {
            released: true,
            ..AT_REST
        };
        assert!(!o.update(asleep, 255, 2000).motors);
    }

    #[test]
    fn busy_clears_with_the_motion_and_a_refused_board_blinks() {
        let mut o = IdleOutputs::new();
        assert!(o.update(MOVING, 25, 0).busy);
        let l = o.update(AT_REST, 25, 1);
        assert!(!l.busy && !l.led && l.motors);
        let refused = Activity {
            released: true,
            refused: true,
            ..AT_REST
        };
        let lit: Vec<u32> = (0..BLINK_PERIOD_MS)
            .filter(|&t| o.update(refused, 25, t).led)
            .collect();
        // Three flashes of 150 ms, then dark until the period ends.
        assert_eq!(lit.len(), 450);
        assert_eq!(lit.first(), Some(&0));
        assert_eq!(lit.last(), Some(&949));
        assert!((0..BLINK_PERIOD_MS).all(|t| !o.update(refused, 25, t).motors));
    }
}
