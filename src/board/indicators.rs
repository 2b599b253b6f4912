//! The busy LED, the busy output and the buzzer.

use stm32f1xx_hal::gpio::{Output, PushPull, PA10, PC13, PC15};

/// Busy LED (PC13, on the board, active low) and busy output (PC15, high while busy,
/// for controllers that run in step): owned by the step preparation task, which sets
/// them every millisecond from the core's decision (`Controller::outputs_now`).
pub struct BusyOutputs {
    pub(super) led: PC13<Output<PushPull>>,
    pub(super) busy_out: PC15<Output<PushPull>>,
}

impl BusyOutputs {
    /// `led`: the LED lit (busy, or the blink code of a refused chip); `busy`: the
    /// busy output high.
    pub fn set(&mut self, led: bool, busy: bool) {
        if led {
            self.led.set_low();
        } else {
            self.led.set_high();
        }
        if busy {
            self.busy_out.set_high();
        } else {
            self.busy_out.set_low();
        }
    }
}

/// The buzzer (PA10, active high), played by the keypad task.
pub struct Indicators {
    pub(super) buzzer: PA10<Output<PushPull>>,
}

impl Indicators {
    pub fn set_buzzer(&mut self, on: bool) {
        if on {
            self.buzzer.set_high();
        } else {
            self.buzzer.set_low();
        }
    }
}
