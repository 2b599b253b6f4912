//! The safety and control inputs on EXTI lines (e-stop, limit switches, feed hold,
//! cycle start): their raw levels and the pending flags of their interrupts.

use super::pins::idr;
use stm32f1xx_hal::pac;

/// Raw input levels, read together.
#[derive(Clone, Copy, Debug, defmt::Format)]
pub struct InputLevels {
    pub estop_open: bool,
    pub limit_x_open: bool,
    pub limit_y_open: bool,
    pub feed_hold_low: bool,
    pub cycle_start_low: bool,
}

/// Safety and control inputs on EXTI: e-stop PB0, limits PB1 and PB3, feed hold PB4,
/// cycle start PB5 (pull-up inputs).
pub struct Inputs {
    pub(super) _owned: (),
}

impl Inputs {
    /// Raw levels: true = switch open / input high.
    pub fn estop_open(&self) -> bool {
        idr(pac::GPIOB::ptr()) & (1 << 0) != 0
    }
    pub fn limit_x_open(&self) -> bool {
        idr(pac::GPIOB::ptr()) & (1 << 1) != 0
    }
    pub fn limit_y_open(&self) -> bool {
        idr(pac::GPIOB::ptr()) & (1 << 3) != 0
    }
    pub fn feed_hold_low(&self) -> bool {
        Self::read_feed_hold_low()
    }
    pub fn cycle_start_low(&self) -> bool {
        Self::read_cycle_start_low()
    }
    /// All input levels in one read of GPIOB (usable from any context).
    pub fn levels() -> InputLevels {
        let idr = idr(pac::GPIOB::ptr());
        InputLevels {
            estop_open: idr & (1 << 0) != 0,
            limit_x_open: idr & (1 << 1) != 0,
            limit_y_open: idr & (1 << 3) != 0,
            feed_hold_low: idr & (1 << 4) == 0,
            cycle_start_low: idr & (1 << 5) == 0,
        }
    }
    /// The feed-hold level read straight from GPIOB, for the EXTI handler (which does
    /// not own the pins). Low = hold.
    pub fn read_feed_hold_low() -> bool {
        idr(pac::GPIOB::ptr()) & (1 << 4) == 0
    }
    /// The cycle-start level straight from GPIOB. Low = pressed.
    pub fn read_cycle_start_low() -> bool {
        idr(pac::GPIOB::ptr()) & (1 << 5) == 0
    }
}

/// Read the EXTI pending bit of line `line` and clear it.
pub fn exti_take_pending(line: u8) -> bool {
    // SAFETY: PR is rc_w1; writing 1 clears only that line.
    unsafe {
        let exti = &*pac::EXTI::ptr();
        let pending = exti.pr().read().bits() & (1 << line) != 0;
        if pending {
            exti.pr().write(|w| w.bits(1 << line));
        }
        pending
    }
}
