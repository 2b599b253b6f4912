//! The safety and control inputs on EXTI lines (e-stop, limit switches, feed hold,
//! cycle start): their raw levels and the pending flags of their interrupts.

use inkstep_core::machine::PinLevels;
use stm32f1xx_hal::gpio::{Input, PullUp, PB0, PB1, PB3, PB4, PB5};
use stm32f1xx_hal::pac;

/// Safety and control inputs on EXTI: e-stop PB0, limits PB1 and PB3, feed hold PB4,
/// cycle start PB5 (pull-up inputs). What a level means (and `$5`/`$215`'s inversion)
/// is the core's: `inkstep_core::machine::InputPolarity`.
pub struct Inputs {
    // Owned so that nothing else reconfigures them; read together through GPIOB.
    pub(super) _estop: PB0<Input<PullUp>>,
    pub(super) _limit_x: PB1<Input<PullUp>>,
    pub(super) _limit_y: PB3<Input<PullUp>>,
    pub(super) _feed_hold: PB4<Input<PullUp>>,
    pub(super) _cycle_start: PB5<Input<PullUp>>,
}

impl Inputs {
    /// Every input's pin level in one read of GPIOB (true = high), usable from any
    /// context (the input interrupts do not own the pins). The board has no Z limit.
    pub fn levels() -> PinLevels {
        // SAFETY: a read of GPIOB's input data register, which has no side effect.
        let idr = unsafe { (*pac::GPIOB::ptr()).idr().read().bits() };
        let high = |pin: u32| idr & (1 << pin) != 0;
        PinLevels {
            estop: high(0),
            limits: [Some(high(1)), Some(high(3)), None],
            feed_hold: high(4),
            cycle_start: high(5),
        }
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
