//! The motion outputs on GPIOA: step, direction and coil pins (PA0-PA7) and the
//! driver enable (PA9) with its polarity (`$4`), and the emergency path that turns
//! them all off from any context.

use super::step_timer::{stop_step_timer, StepTimer};
use core::sync::atomic::{AtomicBool, Ordering};
use stm32f1xx_hal::gpio::{self, ErasedPin, Output, PushPull};
use stm32f1xx_hal::pac;

/// GPIOA bit masks of the motion outputs.
pub const STEP_MASK_X: u32 = 1 << 0;
pub const STEP_MASK_Y: u32 = 1 << 1;
pub const STEP_MASK_Z: u32 = 1 << 2;
pub const DIR_SHIFT: u32 = 3;
pub const MOTION_PINS: u32 = 0xFF;

/// The driver enable pin, PA9.
const ENABLE_PIN: u32 = 9;

/// The GPIOA BSRR word that sets the pins in `high` and clears those in `low` (PA0-PA7).
#[inline(always)]
pub const fn bsrr_word(high: u8, low: u8) -> u32 {
    (high as u32) | ((low as u32) << 16)
}

/// One store to GPIOA's bit set/reset register: the step port's one way to write its
/// pins, from the step interrupt, from any task, and from the emergency path (a panic
/// or the e-stop), which cannot wait for the owner of the pins.
#[inline(always)]
fn write_gpioa(word: u32) {
    // SAFETY: BSRR is write-only and atomic per bit (no read-modify-write, so it is
    // safe against preemption); the callers name only the step port's pins (PA0-PA7,
    // PA9), which nothing else drives.
    unsafe {
        (*pac::GPIOA::ptr()).bsrr().write(|w| w.bits(word));
    }
}

/// The step, direction and coil outputs on PA0-PA7 plus the driver enable on PA9.
///
/// Made only by [`step_outputs`] from the configured pins; writes GPIOA's BSRR
/// directly: one store for all eight pins per interrupt (the HAL writes one pin at a
/// time), no read-modify-write, safe against preemption.
pub struct StepPort {
    _owned: (),
}

impl StepPort {
    /// Set the pins in `high` and clear the pins in `low` among PA0-PA7, in one store.
    #[inline(always)]
    pub fn write(&mut self, high: u8, low: u8) {
        self.write_word(bsrr_word(high, low));
    }

    /// Store a BSRR word made by [`bsrr_word`] (precomputed by the step interrupt).
    #[inline(always)]
    pub fn write_word(&mut self, word: u32) {
        write_gpioa(word);
    }

    /// Enable or disable the stepper drivers. `active_low` is true for A4988-style /EN;
    /// it is remembered for [`drivers_enabled`] and [`emergency_outputs_off`].
    pub fn set_drivers_enabled(&mut self, enabled: bool, active_low: bool) {
        set_enable_polarity(active_low);
        drivers_enabled(enabled);
    }
}

/// The driver-enable polarity (`$4`): true while /EN is active low (the default).
static ENABLE_ACTIVE_LOW: AtomicBool = AtomicBool::new(true);

/// Set the driver-enable polarity; takes effect at the next write of the enable pin.
pub fn set_enable_polarity(active_low: bool) {
    ENABLE_ACTIVE_LOW.store(active_low, Ordering::Relaxed);
}

/// Drivers on or off with the configured polarity: one BSRR store, so any task may
/// call it (the enable pin PA9 belongs to the step port; this touches nothing else).
pub fn drivers_enabled(enabled: bool) {
    let high = enabled != ENABLE_ACTIVE_LOW.load(Ordering::Relaxed);
    write_gpioa(if high {
        1 << ENABLE_PIN
    } else {
        1 << (ENABLE_PIN + 16)
    });
}

/// Every 4-phase coil unpowered (PA0-PA7 low): the motors released at rest in 4-phase
/// mode, where the coils, not a driver's enable, hold them. One BSRR store; call only
/// while no step is in flight (the step interrupt writes these pins).
pub fn coils_off() {
    write_gpioa(MOTION_PINS << 16);
}

/// The motion output pins, configured as push-pull outputs (by [`init`](super::init), and by the
/// interrupt-cost bench, which builds the same parts).
pub struct StepPins {
    pub pins: [ErasedPin<Output<PushPull>>; 8],
    pub enable: gpio::PA9<Output<PushPull>>,
}

/// The step port and step timer from their pins, TIM2 and its stopwatch TIM3. Separate
/// from [`init`](super::init) so that the interrupt-cost bench (bench/isr-cost) builds
/// the very same parts.
pub fn step_outputs(pins: StepPins, tim2: pac::TIM2, tim3: pac::TIM3) -> (StepPort, StepTimer) {
    // The pins are configured and moved in here, so nothing else can take them; the
    // port writes their register from here on. Zero-sized, so that the step
    // interrupt's state stays as small as it was measured (bench/isr-cost/run: the
    // update path takes 2 more instructions when the port carries the pin values).
    let StepPins { pins: _, enable: _ } = pins;
    (StepPort { _owned: () }, StepTimer::new(tim2, tim3))
}

/// Disable every motor driver and drop all step/coil outputs, from any context.
///
/// Used by the panic handler and the e-stop: it touches only GPIOA's atomic set/reset
/// register, so it cannot deadlock on a lock held by the code that failed. With the
/// default `$4=0` (active-low enable) a high ENABLE pin means "disabled"; since the
/// invert setting may be unknown in a panic, it also releases every coil (4-phase
/// motors are then unpowered whatever the setting).
pub fn emergency_outputs_off() {
    // The enable pin's "off" level follows `$4`: high for active-low /EN, low for an
    // active-high enable.
    let off = if ENABLE_ACTIVE_LOW.load(Ordering::Relaxed) {
        1 << ENABLE_PIN
    } else {
        1 << (ENABLE_PIN + 16)
    };
    write_gpioa(off | (MOTION_PINS << 16));
    // The step timer draws the step pulses in step/dir mode.
    stop_step_timer();
}
