//! The busy LED, the busy output and the buzzer.

use super::pins::{bsrr, pin_word};
use stm32f1xx_hal::pac;

/// Busy LED (PC13, active low), busy output (PC15) and buzzer (PA10).
pub struct Indicators {
    pub(super) _owned: (),
}

impl Indicators {
    pub fn set_busy(&mut self, busy: bool) {
        // LED low and output high while busy, in one store.
        bsrr(pac::GPIOC::ptr(), pin_word(13, !busy) | pin_word(15, busy));
    }
    pub fn set_buzzer(&mut self, on: bool) {
        bsrr(pac::GPIOA::ptr(), pin_word(10, on));
    }
}
