//! The halt latch: the one record that the step output is halted, which inputs halted
//! it, and the rule that releases it. Shared by the highest-priority input interrupts
//! (which trip it), the step interrupt (which looks at it and emits nothing while it is
//! set), the step queue's flush and the protocol task (which releases it), so it is one
//! atomic word and every method takes `&self`: the firmware keeps it in a static, the
//! simulator in its board.
//!
//! The rule: an input trips the latch at once, in its interrupt (the e-stop on every
//! edge; a limit switch only on an axis with hard limits armed). The latch is released
//! only when all of these hold at the same moment:
//! - the machine has seen every input that tripped it (the protocol task takes them
//!   with [`HaltLatch::take_tripped`] and shows them to the machine as active, even if
//!   the pin was released again before the task read it: a halted output always comes
//!   with its alarm);
//! - the step queue was flushed since the trip (the steps queued before the halt are
//!   never emitted);
//! - the machine is not in alarm (a soft reset or `$X` cleared it) and the e-stop
//!   input is not active now ([`Serviced::allows_release`], with the pins read by the
//!   shell just before the release, with interrupts off, so that an e-stop pressed
//!   after the protocol task read its inputs is never undone).

#[cfg(doc)]
use crate::controller::Serviced;
use crate::machine::{InputPolarity, PinLevels};
use core::sync::atomic::{AtomicU32, Ordering};

/// Tripped by the e-stop.
const TRIP_ESTOP: u32 = 1;
/// Tripped by a limit switch: bit `1 + axis`.
const TRIP_LIMIT: u32 = 0b1110;
const TRIPPED: u32 = TRIP_ESTOP | TRIP_LIMIT;
/// Axes whose limit switch halts (hard limits armed): bit `4 + axis`.
const ARMED_SHIFT: u32 = 4;
const ARMED: u32 = 0b111 << ARMED_SHIFT;
/// The steps queued before the trip are still queued.
const UNFLUSHED: u32 = 1 << 14;
/// The step output is halted.
const HALTED: u32 = 1 << 31;

/// See the module comment.
#[derive(Debug, Default)]
pub struct HaltLatch(AtomicU32);

/// Inputs that tripped the latch since the protocol task last looked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tripped(u32);

impl Tripped {
    /// `pins` with every input that tripped shown at its active level under
    /// `polarity`, whatever its level now.
    pub fn fold(self, mut pins: PinLevels, polarity: InputPolarity) -> PinLevels {
        if self.0 & TRIP_ESTOP != 0 {
            pins.estop = !polarity.invert_controls;
        }
        for (axis, level) in pins.limits.iter_mut().enumerate() {
            if self.0 & (2 << axis) != 0 {
                *level = Some(!polarity.invert_limits);
            }
        }
        pins
    }
}

impl HaltLatch {
    pub const fn new() -> HaltLatch {
        HaltLatch(AtomicU32::new(0))
    }

    /// The axes (bit 0 X) whose limit switch halts the output: `OutputConfig`'s
    /// `hard_limit_axes`, at boot and whenever the settings change.
    pub fn arm_hard_limits(&self, axes: u8) {
        let armed = (u32::from(axes) << ARMED_SHIFT) & ARMED;
        let _ = self
            .0
            .fetch_update(Ordering::SeqCst, Ordering::Relaxed, |s| {
                Some((s & !ARMED) | armed)
            });
    }

    /// The e-stop input changed (either edge): halt.
    pub fn trip_estop(&self) {
        self.0
            .fetch_or(HALTED | UNFLUSHED | TRIP_ESTOP, Ordering::SeqCst);
    }

    /// The limit switch of `axis` changed (either edge): halt if that axis has hard
    /// limits armed. True when it halted (the shell stops the step output at once).
    pub fn trip_limit(&self, axis: usize) -> bool {
        let bit = 1u32 << (axis & 3);
        if (self.0.load(Ordering::Relaxed) >> ARMED_SHIFT) & bit == 0 {
            return false;
        }
        self.0
            .fetch_or(HALTED | UNFLUSHED | (bit << 1), Ordering::SeqCst);
        true
    }

    /// The step output is halted: no step may start.
    #[inline(always)]
    pub fn is_halted(&self) -> bool {
        self.0.load(Ordering::Relaxed) & HALTED != 0
    }

    /// The inputs that tripped since the last call (the protocol task, before it reads
    /// the pins).
    pub fn take_tripped(&self) -> Tripped {
        Tripped(self.0.fetch_and(!TRIPPED, Ordering::SeqCst) & TRIPPED)
    }

    /// The step queue was flushed: nothing queued before a trip can run any more.
    pub fn flushed(&self) {
        self.0.fetch_and(!UNFLUSHED, Ordering::SeqCst);
    }

    /// Release the latch if the machine allows it (`machine_allows`: after a protocol
    /// run, [`Serviced::allows_release`]) and the rest of the rule of the module
    /// comment holds. True when it was released (the shell turns the drivers back on;
    /// it calls this with interrupts off, so that no e-stop falls between its pin
    /// read and that write).
    pub fn release(&self, machine_allows: bool) -> bool {
        if !machine_allows {
            return false;
        }
        self.0
            .fetch_update(Ordering::SeqCst, Ordering::Relaxed, |s| {
                let releasable = s & HALTED != 0 && s & (TRIPPED | UNFLUSHED) == 0;
                releasable.then_some(s & !HALTED)
            })
            .is_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::Serviced;

    const AT_REST: PinLevels = PinLevels {
        estop: false,
        limits: [Some(false), Some(false), None],
        feed_hold: true,
        cycle_start: true,
    };
    const POLARITY: InputPolarity = InputPolarity {
        invert_limits: false,
        invert_controls: false,
    };

    fn done(alarmed: bool) -> Serviced {
        Serviced {
            outputs: None,
            servo_pulse_us: None,
            alarmed,
            polarity: POLARITY,
            more: false,
            quiet: true,
        }
    }

    #[test]
    fn a_limit_halts_only_on_an_armed_axis() {
        let l = HaltLatch::new();
        assert!(!l.trip_limit(0));
        assert!(!l.is_halted());
        l.arm_hard_limits(0b10);
        assert!(!l.trip_limit(0));
        assert!(l.trip_limit(1));
        assert!(l.is_halted());
        let pins = l.take_tripped().fold(AT_REST, POLARITY);
        assert_eq!(pins.limits, [Some(false), Some(true), None]);
        // Arming again keeps the halt.
        l.arm_hard_limits(0);
        assert!(l.is_halted());
    }

    #[test]
    fn a_tripped_input_is_shown_active_once() {
        let l = HaltLatch::new();
        l.trip_estop();
        let inverted = InputPolarity {
            invert_controls: true,
            ..POLARITY
        };
        assert!(!l.take_tripped().fold(AT_REST, inverted).estop);
        assert_eq!(l.take_tripped().fold(AT_REST, POLARITY), AT_REST);
    }

    #[test]
    fn release_waits_for_the_alarm_the_flush_and_the_estop() {
        let l = HaltLatch::new();
        l.trip_estop();
        // Not yet seen by the machine.
        assert!(!l.release(done(false).allows_release(AT_REST)));
        let _ = l.take_tripped();
        // Not flushed.
        assert!(!l.release(done(false).allows_release(AT_REST)));
        l.flushed();
        // In alarm.
        assert!(!l.release(done(true).allows_release(AT_REST)));
        // E-stop still pressed.
        let pressed = PinLevels {
            estop: true,
            ..AT_REST
        };
        assert!(!l.release(done(false).allows_release(pressed)));
        assert!(l.is_halted());
        assert!(l.release(done(false).allows_release(AT_REST)));
        assert!(!l.is_halted());
        // Nothing to release.
        assert!(!l.release(done(false).allows_release(AT_REST)));
    }
}
