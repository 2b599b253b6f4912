//! The busy LED, the busy output and the buzzer.

use stm32f1xx_hal::gpio::{Output, PushPull, PA10, PC13, PC15};

/// Busy LED (PC13, on the board, active low), busy output (PC15, high while busy, for
/// controllers that run in step) and buzzer (PA10, active high).
pub struct Indicators {
    pub(super) led: PC13<Output<PushPull>>,
    pub(super) busy_out: PC15<Output<PushPull>>,
    pub(super) buzzer: PA10<Output<PushPull>>,
}

impl Indicators {
    pub fn set_busy(&mut self, busy: bool) {
        if busy {
            self.led.set_low();
            self.busy_out.set_high();
        } else {
            self.led.set_high();
            self.busy_out.set_low();
        }
    }
    pub fn set_buzzer(&mut self, on: bool) {
        if on {
            self.buzzer.set_high();
        } else {
            self.buzzer.set_low();
        }
    }
}
