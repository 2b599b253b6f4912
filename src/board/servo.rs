//! The pen servo: TIM1 CH1 on PA8 at 50 Hz.

use stm32f1xx_hal::pac;
use stm32f1xx_hal::timer::PwmChannel;

/// The pen servo on PA8 (TIM1 CH1), 50 Hz.
pub struct PenServo {
    pub(super) pwm: PwmChannel<pac::TIM1, 0>,
}

impl PenServo {
    /// Set the pulse width in microseconds (typically 500..2500 for 0..180 degrees).
    pub fn set_pulse_us(&mut self, us: u32) {
        let max = u32::from(self.pwm.get_max_duty());
        // 20 ms period: duty = us / 20000 of max.
        let duty = (max * us.min(20_000)) / 20_000;
        self.pwm.set_duty(duty as u16);
    }
}
