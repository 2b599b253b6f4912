//! TIM2, the step timer: it draws the step pulses itself in step/dir mode (PWM on
//! CH1-CH3, armed one period ahead) and raises one interrupt per step event.

use super::{STEP_TIMER_HZ, SYSCLK_HZ};
use inkstep_core::stepper::MAX_RELOAD;
use stm32f1xx_hal::pac;

/// The update event flag (UIF): a period has ended.
const EVENT_UPDATE: u32 = 1;

// TIM2 register values (RM0008 section 15.4). PWM mode 1 with CCR preload on channels
// 1-3 (the step pins PA0-PA2): a channel is active from the update event until the count
// reaches its CCR, so a CCR of `pulse` gives one pulse of exactly that width at the
// start of the period and a CCR of 0 gives none.
const CCMR1_STEP_XY: u32 = (0b110 << 4) | (1 << 3) | (0b110 << 12) | (1 << 11);
const CCMR2_STEP_Z: u32 = (0b110 << 4) | (1 << 3);
const CCER_STEP_ENABLE: u32 = (1 << 0) | (1 << 4) | (1 << 8);
const DIER_UPDATE: u32 = 1;

/// Point PA0-PA2 at the step timer (alternate function: the timer shapes the pulses) or
/// back at GPIO (4-phase coils written by the interrupt). Only at rest.
fn set_step_pins_to_timer(timer: bool) {
    let nibble = if timer { 0xB } else { 0x3 }; // AF / GPIO push-pull, 50 MHz
    critical_section::with(|_| {
        // SAFETY: PA0-PA2's configuration nibbles belong to the step port; the
        // read-modify-write of CRL happens with interrupts off.
        unsafe {
            (*pac::GPIOA::ptr()).crl().modify(|r, w| {
                w.bits((r.bits() & !0xFFF) | nibble | (nibble << 4) | (nibble << 8))
            });
        }
    });
}

/// TIM2 as the step timer, counting at [`STEP_TIMER_HZ`].
///
/// In step/dir mode the timer itself draws every step pulse: the interrupt at the start
/// of a period arms, through the CCR preload registers, the channels that pulse at the
/// start of the next period, so pulse timing and width are exact to the tick and need
/// no interrupt of their own. In 4-phase mode the pins are GPIO and the interrupt writes
/// the coils. One interrupt per step event either way.
pub struct StepTimer {
    tim: pac::TIM2,
    /// Pulse width in ticks, the CCR value of an armed channel.
    pulse: u32,
    /// CCR1-CCR3 for each step mask (bit i = axis i): `pulse` or 0 (a fourth word
    /// pads each row to 16 bytes, so the interrupt indexes it with one shift).
    arm_table: [[u32; 4]; 8],
}

impl StepTimer {
    pub(super) fn new(tim: pac::TIM2) -> Self {
        // SAFETY: enabling the TIM2 clock; RCC is otherwise owned by the HAL but this
        // bit is not touched by it after freeze.
        unsafe {
            let rcc = &*pac::RCC::ptr();
            rcc.apb1enr().modify(|_, w| w.tim2en().set_bit());
            rcc.apb1rstr().modify(|_, w| w.tim2rst().set_bit());
            rcc.apb1rstr().modify(|_, w| w.tim2rst().clear_bit());
        }
        let psc = SYSCLK_HZ / STEP_TIMER_HZ - 1;
        // SAFETY: raw writes of documented TIM2 register values (RM0008 15.4) to the
        // timer this struct owns, while it is stopped.
        unsafe {
            tim.psc().write(|w| w.bits(psc));
            tim.arr().write(|w| w.bits(0xFFFF));
            tim.ccmr1_output().write(|w| w.bits(CCMR1_STEP_XY));
            tim.ccmr2_output().write(|w| w.bits(CCMR2_STEP_Z));
            for n in 0..4 {
                tim.ccr(n).write(|w| w.bits(0));
            }
            // Apply the prescaler and the zero CCRs now, without an interrupt for it.
            tim.egr().write(|w| w.ug().set_bit());
            tim.sr().write(|w| w.bits(0));
            // No ARR preload: the reload written in the update interrupt is the length
            // of the period that has just begun (the executor's contract), and
            // `set_period` guards against a count already past the new value. URS: only
            // counter overflows raise the update interrupt, not UG.
            tim.cr1().write(|w| w.arpe().clear_bit().urs().set_bit());
            tim.dier().write(|w| w.bits(DIER_UPDATE));
        }
        let mut t = Self {
            tim,
            pulse: 0,
            arm_table: [[0; 4]; 8],
        };
        t.set_pulse_ticks(720);
        t
    }

    /// Output mode: in step/dir mode the timer drives PA0-PA2 (with `step_invert`
    /// inverting a channel's polarity, bit i = axis i); in 4-phase mode it lets go of
    /// them. Only at rest.
    pub fn configure_outputs(&mut self, step_dir: bool, step_invert: u8) {
        let inv = u32::from(step_invert);
        let polarity = ((inv & 1) << 1) | ((inv & 2) << 4) | ((inv & 4) << 7);
        let ccer = if step_dir {
            CCER_STEP_ENABLE | polarity
        } else {
            0
        };
        // SAFETY: documented CCER bits of the channels this timer owns.
        self.tim.ccer().write(|w| unsafe { w.bits(ccer) });
        set_step_pins_to_timer(step_dir);
    }

    /// Set the pulse width in timer ticks (at rest; taken by the next armed pulse).
    pub fn set_pulse_ticks(&mut self, ticks: u16) {
        self.pulse = u32::from(ticks.max(1));
        for (mask, row) in (0u8..).zip(self.arm_table.iter_mut()) {
            for (axis, ccr) in row.iter_mut().take(3).enumerate() {
                *ccr = if mask >> axis & 1 != 0 { self.pulse } else { 0 };
            }
        }
    }

    /// The pulse width in ticks.
    pub fn pulse_ticks(&self) -> u32 {
        self.pulse
    }

    /// Arm the channels of `steps` (bit i = axis i) to pulse at the start of the next
    /// period, and disarm the others (CCR preloads, taken at the next update).
    #[inline(always)]
    pub fn arm_pulses(&mut self, steps: u8) {
        let [x, y, z, _] = self.arm_table[usize::from(steps & 0b111)];
        // SAFETY: CCR values for the step channels.
        unsafe {
            self.tim.ccr1().write(|w| w.bits(x));
            self.tim.ccr2().write(|w| w.bits(y));
            self.tim.ccr3().write(|w| w.bits(z));
        }
    }

    /// Program the period of the next step interval, in ticks: 2..=65536, which the
    /// core's executor guarantees (so no clamp costs the interrupt time here).
    #[inline(always)]
    pub fn set_period(&mut self, ticks: u32) {
        debug_assert!((2..=MAX_RELOAD).contains(&ticks));
        let arr = ticks.wrapping_sub(1);
        // SAFETY: any 16-bit auto-reload value is valid; `ticks` is 2..=0x10000.
        self.tim.arr().write(|w| unsafe { w.bits(arr) });
        // Interrupt latency already counted past the new end: end the period now
        // rather than wrapping through 65536 ticks.
        if self.tim.cnt().read().bits() >= arr {
            // SAFETY: any 16-bit count is valid.
            self.tim.cnt().write(|w| unsafe { w.bits(arr) });
        }
    }

    pub fn start(&mut self) {
        // SAFETY: any 16-bit count is valid.
        self.tim.cnt().write(|w| unsafe { w.bits(0) });
        self.tim.cr1().modify(|_, w| w.cen().set_bit());
    }

    pub fn stop(&mut self) {
        self.tim.cr1().modify(|_, w| w.cen().clear_bit());
    }

    /// Stop at once with every step output back at its idle level (e-stop, abort): the
    /// armed channels are cleared and loaded immediately, cutting a pulse in flight.
    pub fn stop_now(&mut self) {
        self.arm_pulses(0);
        self.tim.egr().write(|w| w.ug().set_bit());
        self.stop();
    }

    pub fn is_running(&self) -> bool {
        self.tim.cr1().read().cen().bit_is_set()
    }

    /// Whether an update event raised the interrupt (false for a software pend);
    /// clears the update flag only if it was seen, so an update that arrives between
    /// the read and the write (during a pend) is not lost.
    #[inline(always)]
    pub fn take_update(&mut self) -> bool {
        let seen = self.tim.sr().read().bits() & EVENT_UPDATE;
        // SAFETY: SR's flags are rc_w0: a 0 clears, a 1 leaves a flag alone (bits
        // 15:0 only), so this clears the update flag and nothing else.
        self.tim.sr().write(|w| unsafe { w.bits(!seen & 0xFFFF) });
        seen != 0
    }
}

/// Stop the step timer from any context (the e-stop and hard-limit interrupts): one
/// store, CEN cleared and URS kept (StepTimer's configuration).
pub fn stop_step_timer() {
    // SAFETY: a single store to TIM2's CR1.
    unsafe {
        (*pac::TIM2::ptr()).cr1().write(|w| w.bits(1 << 2));
    }
}

/// Disarm every step channel of the step timer from a task, inside the critical section
/// that flushes the step queue: a pulse armed for a command that was just dropped must
/// not fire.
pub fn disarm_step_pulses() {
    // SAFETY: CCR preload writes of TIM2's step channels; called with interrupts off, so
    // the step interrupt (their only other writer) cannot be halfway through arming.
    unsafe {
        let tim = &*pac::TIM2::ptr();
        tim.ccr1().write(|w| w.bits(0));
        tim.ccr2().write(|w| w.bits(0));
        tim.ccr3().write(|w| w.bits(0));
    }
}
