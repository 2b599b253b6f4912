//! The Blue Pill board: the pin map and every peripheral's setup, in one place.
//!
//! This is the only module that knows which pin does what. Everything it hands out is
//! a small owner of one job (step port, keypad matrix, LCD, USB, ...) whose methods are
//! plain register accesses; all decisions are taken in `inkstep-core`.
//!
//! | pin      | signal                          | notes                                          |
//! |----------|---------------------------------|------------------------------------------------|
//! | PA0      | X STEP  (4-phase: X coil A)     | TIM2 CH1-CH3 in step/dir mode: the timer draws |
//! | PA1      | Y STEP  (4-phase: X coil B)     | the pulses; GPIO in 4-phase mode. All motion   |
//! | PA2      | Z STEP  (4-phase: X coil C)     | outputs on GPIOA: one BSRR store sets the rest |
//! | PA3      | X DIR   (4-phase: X coil D)     |                                                |
//! | PA4      | Y DIR   (4-phase: Y coil A)     |                                                |
//! | PA5      | Z DIR   (4-phase: Y coil B)     |                                                |
//! | PA6      | (4-phase: Y coil C)             | unused in step/dir mode                        |
//! | PA7      | (4-phase: Y coil D)             | unused in step/dir mode                        |
//! | PA8      | pen servo PWM (TIM1 CH1, 50 Hz) | 5 V servo signal is fine from 3.3 V            |
//! | PA9      | stepper ENABLE                  | active low (A4988/DRV8825 /EN); `$4` inverts   |
//! | PA10     | buzzer                          | active high, through a transistor              |
//! | PA11/12  | USB D-/D+                       | CDC-ACM serial; PA12 pulled low at boot        |
//! | PA13/14  | SWDIO/SWCLK                     | probe-rs; JTAG is disabled, SWD stays          |
//! | PA15     | keypad column 3                 | open-drain, driven low to scan                 |
//! | PB0      | E-STOP input (EXTI0)            | pull-up; wire NC to GND, open = stop           |
//! | PB1      | X limit/home switch (EXTI1)     | pull-up; NC to GND, `$5` inverts               |
//! | PB3      | Y limit/home switch (EXTI3)     | pull-up; NC to GND                             |
//! | PB4      | feed hold / SYNC in (EXTI4)     | pull-up; low = pause (the seed's SYNC input)   |
//! | PB5      | cycle start (EXTI5)             | pull-up; falling edge = resume                 |
//! | PB6-PB9  | keypad rows 1-4                 | pull-up inputs, read together from GPIOB IDR   |
//! | PB10     | keypad column 1                 | open-drain                                     |
//! | PB11     | keypad column 2                 | open-drain                                     |
//! | PB12     | LCD CS (ST7920 RS)              | active high                                    |
//! | PB13     | LCD SCK (ST7920 E)              | SPI2 mode 0, 281 kHz                           |
//! | PB15     | LCD MOSI (ST7920 R/W)           | ST7920 PSB tied low (serial mode)              |
//! | PC13     | busy LED (on board)             | active low                                     |
//! | PC14     | keypad column 4                 | open-drain (low-speed pin, fine for a keypad)  |
//! | PC15     | busy output                     | high while moving, for syncing controllers     |

use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, Ordering};
use stm32f1xx_hal::{
    flash::FlashExt,
    gpio::{self, ErasedPin, Input, Output, PushPull},
    pac,
    prelude::*,
    rcc,
    spi::{Mode, Phase, Polarity, Spi},
    timer::{Channel, PwmChannel, Tim1NoRemap},
    usb::{Peripheral, UsbBus, UsbBusType},
};
use usb_device::{bus::UsbBusAllocator, prelude::*};

/// System clock: 72 MHz from the 8 MHz crystal (PLL x9), APB1 36 MHz, USB 48 MHz.
pub const SYSCLK_HZ: u32 = 72_000_000;
/// The step timer (TIM2) counts at the full timer clock (APB1 x2 = 72 MHz, prescaler 1):
/// waits are exact to 14 ns; longer waits than 16 bits are split by the core's executor.
pub const STEP_TIMER_HZ: u32 = 72_000_000;
/// SPI clock for the ST7920: the HAL picks 36 MHz / 128 = 281 kHz, so one 24-bit
/// serial write (85 µs) outlasts the controller's 72 µs execution time and the bytes
/// can stream back to back without delays (see core::screens::st7920).
pub const LCD_SPI_HZ: u32 = 300_000;
/// Watchdog timeout: long enough for the slowest task period, short enough to matter.
pub const WATCHDOG_MS: u32 = 500;

/// GPIOA bit masks of the motion outputs.
pub const STEP_MASK_X: u32 = 1 << 0;
pub const STEP_MASK_Y: u32 = 1 << 1;
pub const STEP_MASK_Z: u32 = 1 << 2;
pub const DIR_SHIFT: u32 = 3;
pub const MOTION_PINS: u32 = 0xFF;

/// The GPIOA BSRR word that sets the pins in `high` and clears those in `low` (PA0-PA7).
#[inline(always)]
pub const fn bsrr_word(high: u8, low: u8) -> u32 {
    (high as u32) | ((low as u32) << 16)
}

/// The step, direction and coil outputs on PA0-PA7 plus the driver enable on PA9.
///
/// Made only by [`init`] (or [`step_outputs`]), which configure the pins; writes
/// GPIOA's BSRR directly: one store per interrupt, no read-modify-write, safe against
/// preemption.
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
        // SAFETY: BSRR is write-only and atomic per bit; this struct owns PA0-PA7 and
        // `bsrr_word` only makes words for those pins.
        unsafe {
            (*pac::GPIOA::ptr()).bsrr().write(|w| w.bits(word));
        }
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
    bsrr(pac::GPIOA::ptr(), pin_word(9, high));
}

/// The motion output pins, configured as push-pull outputs (for the interrupt-cost
/// bench, which configures them through the HAL; [`init`] writes the registers).
pub struct StepPins {
    pub pins: [ErasedPin<Output<PushPull>>; 8],
    pub enable: gpio::PA9<Output<PushPull>>,
}

/// The step port and step timer from their pins and TIM2. Separate from [`init`] so
/// that the interrupt-cost bench (bench/isr-cost) builds the very same parts.
pub fn step_outputs(pins: StepPins, tim2: pac::TIM2) -> (StepPort, StepTimer) {
    // The pins are configured; the port writes their registers from here on.
    let StepPins { pins: _, enable: _ } = pins;
    (StepPort { _owned: () }, StepTimer::new(tim2))
}

/// A GPIO port's register block (GPIOA, GPIOB and GPIOC share the layout).
type GpioRegs = pac::gpioa::RegisterBlock;

/// One store to a GPIO port's bit set/reset register.
#[inline(always)]
fn bsrr(port: *const GpioRegs, word: u32) {
    // SAFETY: BSRR is write-only and atomic per bit; callers only name pins that their
    // owner (a struct made by `init`) drives.
    unsafe {
        (*port).bsrr().write(|w| w.bits(word));
    }
}

/// The BSRR word that drives pin `n` high or low.
#[inline(always)]
const fn pin_word(n: u32, high: bool) -> u32 {
    if high {
        1 << n
    } else {
        1 << (n + 16)
    }
}

/// A port's input data register.
#[inline(always)]
fn idr(port: *const GpioRegs) -> u32 {
    // SAFETY: read-only access to an input register.
    unsafe { (*port).idr().read().bits() }
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
    let off = pin_word(9, ENABLE_ACTIVE_LOW.load(Ordering::Relaxed));
    // SAFETY: a single store to GPIOA's write-only BSRR.
    unsafe {
        (*pac::GPIOA::ptr())
            .bsrr()
            .write(|w| w.bits(off | (MOTION_PINS << 16)));
    }
    // The step timer draws the step pulses in step/dir mode.
    stop_step_timer();
}

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
    fn new(tim: pac::TIM2) -> Self {
        // SAFETY: enabling the TIM2 clock; RCC is otherwise owned by the HAL but this
        // bit is not touched by it after freeze.
        unsafe {
            let rcc = &*pac::RCC::ptr();
            rcc.apb1enr().modify(|_, w| w.tim2en().set_bit());
            rcc.apb1rstr().modify(|_, w| w.tim2rst().set_bit());
            rcc.apb1rstr().modify(|_, w| w.tim2rst().clear_bit());
        }
        let psc = SYSCLK_HZ / STEP_TIMER_HZ - 1;
        // SAFETY (all raw writes below): documented TIM2 register values.
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
        debug_assert!((2..=0x1_0000).contains(&ticks));
        let arr = ticks.wrapping_sub(1);
        self.tim.arr().write(|w| unsafe { w.bits(arr) });
        // Interrupt latency already counted past the new end: end the period now
        // rather than wrapping through 65536 ticks.
        if self.tim.cnt().read().bits() >= arr {
            self.tim.cnt().write(|w| unsafe { w.bits(arr) });
        }
    }

    pub fn start(&mut self) {
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
        // rc_w0 flags: a 0 clears, a 1 leaves a flag alone (bits 15:0 only).
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

/// The pen servo on PA8 (TIM1 CH1), 50 Hz.
pub struct PenServo {
    pwm: PwmChannel<pac::TIM1, 0>,
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

/// The 4x4 keypad: rows PB6-PB9 (pull-up inputs), columns PB10, PB11, PA15, PC14 (open drain).
pub struct KeypadMatrix {
    _owned: (),
}

impl KeypadMatrix {
    pub const COLUMNS: usize = 4;

    /// Drive column `col` low (all others released). The rows settle within a few µs,
    /// which is why the scan task reads them on its next tick rather than busy-waiting.
    pub fn select_column(&mut self, col: usize) {
        // One BSRR word per port: the selected column low, the others released high
        // (a pin is never named in both halves, where setting would win).
        let (b, a, c) = match col {
            0 => (pin_word(10, false) | pin_word(11, true), 1 << 15, 1 << 14),
            1 => (pin_word(10, true) | pin_word(11, false), 1 << 15, 1 << 14),
            2 => (3 << 10, pin_word(15, false), 1 << 14),
            _ => (3 << 10, 1 << 15, pin_word(14, false)),
        };
        bsrr(pac::GPIOB::ptr(), b);
        bsrr(pac::GPIOA::ptr(), a);
        bsrr(pac::GPIOC::ptr(), c);
    }

    /// Row bits of the selected column: bit r set = key in row r pressed (active low).
    pub fn read_rows(&self) -> u8 {
        (!(idr(pac::GPIOB::ptr()) >> 6) & 0x0F) as u8
    }
}

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
    _owned: (),
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

/// Busy LED (PC13, active low), busy output (PC15) and buzzer (PA10).
pub struct Indicators {
    _owned: (),
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

/// The independent watchdog (IWDG, 40 kHz LSI), started by [`init`] with a
/// [`WATCHDOG_MS`] timeout; the keypad task feeds it.
///
/// Register writes instead of the HAL's `IndependentWatchdog`, whose prescaler search
/// runs (with its panics) at boot: here it is done at compile time, with the same
/// result (prescaler /8, reload 2500 for 500 ms).
pub struct Watchdog {
    iwdg: pac::IWDG,
}

impl Watchdog {
    const KR_ACCESS: u16 = 0x5555;
    const KR_RELOAD: u16 = 0xAAAA;
    const KR_START: u16 = 0xCCCC;
    /// Prescaler code and reload for `ms`: the smallest divider (4 << pr) whose longest
    /// period (4096 ticks) reaches `ms`, the reload scaled to it.
    const fn period_ms(pr: u32) -> u32 {
        4096 * (4 << pr) / 40
    }
    const fn timing(ms: u32) -> (u16, u16) {
        let mut pr = 0;
        while pr < 6 && Self::period_ms(pr) < ms {
            pr += 1;
        }
        let rl = ms * 0xFFF / Self::period_ms(pr);
        // Both fit 16 bits: pr <= 6, rl <= 0xFFF.
        (pr as u16, if rl > 0xFFF { 0xFFF } else { rl as u16 })
    }
    const TIMING: (u16, u16) = Self::timing(WATCHDOG_MS);

    fn start(iwdg: pac::IWDG) -> Self {
        let (pr, rl) = Self::TIMING;
        // SAFETY: IWDG key, prescaler and reload registers take any of these values.
        unsafe {
            iwdg.kr().write(|w| w.bits(Self::KR_ACCESS));
            iwdg.pr().write(|w| w.bits(pr));
            iwdg.rlr().write(|w| w.bits(rl));
            iwdg.kr().write(|w| w.bits(Self::KR_RELOAD));
            iwdg.kr().write(|w| w.bits(Self::KR_START));
        }
        Self { iwdg }
    }

    /// Reload the counter.
    pub fn feed(&mut self) {
        // SAFETY: writing the reload key only restarts the countdown.
        unsafe { self.iwdg.kr().write(|w| w.bits(Self::KR_RELOAD)) };
    }
}

// The HAL's search gives prescaler /8, reload 2500 for 500 ms.
const _: () = assert!(matches!(Watchdog::timing(500), (1, 2500)));

/// The LCD link: SPI2, transmit only (the ST7920's serial mode has no read-back),
/// and the controller's chip select on PB12, which is active high.
pub struct LcdSpi {
    spi: Spi<pac::SPI2, u8>,
}

impl LcdSpi {
    /// Send `bytes` as one transaction: chip select raised around them.
    pub fn write(&mut self, bytes: &[u8]) -> Result<(), stm32f1xx_hal::spi::Error> {
        bsrr(pac::GPIOB::ptr(), pin_word(12, true));
        let sent = self.spi.write(bytes);
        bsrr(pac::GPIOB::ptr(), pin_word(12, false));
        sent
    }
}

/// Bring the ST7920 up in graphics mode: the st7920 crate's sequence (its reset wait
/// on a tied reset pin, then basic function set, display on, clear, entry mode,
/// extended function set, graphics on, each followed by its execution time), without
/// building that crate's 1 KB frame buffer. Blocking: only for the lowest-priority task.
pub fn lcd_init(spi: &mut LcdSpi) -> Result<(), stm32f1xx_hal::spi::Error> {
    /// (instruction, wait after it in µs)
    const STEPS: [(u8, u32); 6] = [
        (0x30, 200),
        (0x0C, 100),
        (0x01, 10_000),
        (0x06, 100),
        (0x34, 10_000),
        (0x36, 100_000),
    ];
    const CYCLES_PER_US: u32 = SYSCLK_HZ / 1_000_000;
    cortex_m::asm::delay(80_000 * CYCLES_PER_US);
    for (cmd, wait_us) in STEPS {
        // One serial frame: command start byte, high nibble, low nibble.
        spi.write(&[0xF8, cmd & 0xF0, cmd << 4])?;
        cortex_m::asm::delay(wait_us * CYCLES_PER_US);
    }
    Ok(())
}

pub type Usb = UsbDevice<'static, UsbBusType>;
/// The CDC serial port. Its receive store holds one 64-byte packet (the class default
/// is 128): both images read it with a 64-byte buffer, which empties it, and it takes
/// the next packet from the endpoint only once empty (until then the host is NAKed).
/// The transmit store keeps the default 128 bytes: it holds output while the endpoint
/// is busy, and bytes it refuses are dropped.
pub type UsbSerial =
    usbd_serial::SerialPort<'static, UsbBusType, [u8; 64], usbd_serial::DefaultBufferStore>;

/// The 'static homes of the USB stack (an RTIC init local): the bus allocator the
/// device and the class borrow, and the device and the serial port themselves, built
/// in place and handed out by reference rather than moved through `init`.
pub struct UsbCells {
    bus: MaybeUninit<UsbBusAllocator<UsbBusType>>,
    dev: MaybeUninit<Usb>,
    serial: MaybeUninit<UsbSerial>,
}

impl UsbCells {
    pub const fn new() -> Self {
        Self {
            bus: MaybeUninit::uninit(),
            dev: MaybeUninit::uninit(),
            serial: MaybeUninit::uninit(),
        }
    }
}

impl Default for UsbCells {
    fn default() -> Self {
        Self::new()
    }
}

/// Flash pages are 1 KB on the medium-density STM32F103 (RM0008 3.3.3).
pub const FLASH_PAGE_SIZE: u32 = 1024;
/// The chip's flash: 128 KB on the STM32F103CB this firmware is built for.
pub const FLASH_SIZE: u32 = 128 * 1024;

/// The settings store's flash pages, as chip flash offsets (0 = 0x0800_0000, how the
/// store addresses them). memory.x places them (`_settings_start`, `_settings_end`) and
/// links the program below them; this reads the symbols, so their place is said once.
pub fn settings_pages() -> core::ops::Range<u32> {
    extern "C" {
        static _settings_start: u8;
        static _settings_end: u8;
    }
    // Only the symbols' addresses are taken, never their contents.
    let start = core::ptr::addr_of!(_settings_start) as u32;
    let end = core::ptr::addr_of!(_settings_end) as u32;
    (start - FLASH_BASE)..(end - FLASH_BASE)
}

/// The flash size the chip reports (its F_SIZE register, RM0008 30.1), in KB: 128 on a
/// CB, 64 on a C8.
pub fn flash_size_kb() -> u32 {
    const F_SIZE: *const u16 = 0x1FFF_F7E0 as *const u16;
    // SAFETY: F_SIZE is a read-only factory register, always mapped.
    u32::from(unsafe { core::ptr::read_volatile(F_SIZE) })
}

/// Pin configuration nibbles (RM0008 9.2: CNF[1:0] MODE[1:0]; outputs at 50 MHz, the
/// same values as the HAL's pin modes). A pull-up input also needs its ODR bit set.
const IN_FLOAT: u32 = 0x4;
const IN_PULL: u32 = 0x8;
const OUT_PP: u32 = 0x3;
const OUT_OD: u32 = 0x7;
const AF_PP: u32 = 0xB;

/// A configuration register from the nibbles of its eight pins (lowest pin first).
const fn cr(n: [u32; 8]) -> u32 {
    let mut v = 0;
    let mut i = 0;
    while i < 8 {
        v |= n[i] << (4 * i);
        i += 1;
    }
    v
}

/// GPIOA: PA0-PA7 motion outputs; PA8 servo (TIM1 CH1); PA9 driver enable, high =
/// disabled; PA10 buzzer; PA11/PA12 USB (PA12 first driven low, see `init`); PA13/14
/// SWD as reset; PA15 keypad column 3, released high.
const PA_CRH: [u32; 8] = [
    AF_PP, OUT_PP, OUT_PP, IN_FLOAT, OUT_PP, IN_FLOAT, IN_FLOAT, OUT_OD,
];
const PA_CRH_USB: u32 = (cr(PA_CRH) & !(0xF << 16)) | (IN_FLOAT << 16);
/// (port, ODR, CRL, CRH) of GPIOA, GPIOB and GPIOC, the pin table at the top.
const PORTS: [(*const GpioRegs, u32, u32, u32); 3] = [
    (
        pac::GPIOA::ptr(),
        (1 << 9) | (1 << 15),
        cr([OUT_PP; 8]),
        cr(PA_CRH),
    ),
    // PB0, PB1, PB3-PB5 switch inputs and PB6-PB9 keypad rows with pull-ups; PB2
    // (BOOT1) as reset; PB10/PB11 keypad columns released high; PB12 LCD CS low;
    // PB13/PB15 SPI2 SCK/MOSI; PB14 unused.
    (
        pac::GPIOB::ptr(),
        0x0FFB,
        cr([
            IN_PULL, IN_PULL, IN_FLOAT, IN_PULL, IN_PULL, IN_PULL, IN_PULL, IN_PULL,
        ]),
        cr([
            IN_PULL, IN_PULL, OUT_OD, OUT_OD, OUT_PP, AF_PP, IN_FLOAT, AF_PP,
        ]),
    ),
    // PC13 busy LED off (high), PC14 keypad column 4 released high, PC15 busy out low.
    (
        pac::GPIOC::ptr(),
        (1 << 13) | (1 << 14),
        cr([IN_FLOAT; 8]),
        cr([
            IN_FLOAT, IN_FLOAT, IN_FLOAT, IN_FLOAT, IN_FLOAT, OUT_PP, OUT_OD, OUT_PP,
        ]),
    ),
];

/// Everything `init` hands to the RTIC app.
pub struct Board {
    pub step_port: StepPort,
    pub step_timer: StepTimer,
    pub servo: PenServo,
    pub keypad: KeypadMatrix,
    pub inputs: Inputs,
    pub indicators: Indicators,
    pub lcd_spi: LcdSpi,
    pub usb: &'static mut Usb,
    pub serial: &'static mut UsbSerial,
    pub watchdog: Watchdog,
    pub flash: SettingsFlash,
    pub sysclk_hz: u32,
}

/// Bring up the clocks and every peripheral. Called once from `init` with interrupts off.
///
/// `usb` is the 'static home of the USB stack (an RTIC init local); each call needs
/// its own (init runs once).
pub fn init(dp: pac::Peripherals, usb: &'static mut UsbCells) -> Board {
    let mut flash = dp.FLASH.constrain();
    let mut rcc = dp.RCC.freeze(
        rcc::Config::hse(8.MHz())
            .sysclk(SYSCLK_HZ.Hz())
            .hclk(SYSCLK_HZ.Hz())
            .pclk1(36.MHz())
            .pclk2(72.MHz()),
        &mut flash.acr,
    );
    let sysclk_hz = rcc.clocks.sysclk().raw();

    let mut afio = dp.AFIO.constrain(&mut rcc);
    // Clocks on and ports reset by the HAL; the pin modes are written below.
    let mut gpioa = dp.GPIOA.split(&mut rcc);
    let mut gpiob = dp.GPIOB.split(&mut rcc);
    let _ = dp.GPIOC.split(&mut rcc);
    let exti = dp.EXTI;

    // JTAG off, SWD on: frees PA15, PB3, PB4.
    let _ = afio.mapr.disable_jtag(gpioa.pa15, gpiob.pb3, gpiob.pb4);

    // Every pin's mode in one store per configuration register, the output levels
    // first (see the pin table above; `PORTS`). PA12 (USB D+) starts as an output
    // driven low: the re-enumeration pulse below.
    for (port, odr, crl, crh) in PORTS {
        // SAFETY: the ports were just reset; these are their documented registers and
        // the values configure only the pins in the table.
        unsafe {
            (*port).odr().write(|w| w.bits(odr));
            (*port).crl().write(|w| w.bits(crl));
            (*port).crh().write(|w| w.bits(crh));
        }
    }
    let (step_port, step_timer) = (StepPort { _owned: () }, StepTimer::new(dp.TIM2));

    // The peripherals' pins as the HAL's types (their nibbles are already set).
    let servo_pin = gpioa.pa8.into_alternate_push_pull(&mut gpioa.crh);
    let mut pwm = dp
        .TIM1
        .pwm_hz::<Tim1NoRemap, _, _>(servo_pin, &mut afio.mapr, 50.Hz(), &mut rcc);
    pwm.enable(Channel::C1);
    let servo = PenServo { pwm: pwm.split() };

    let keypad = KeypadMatrix { _owned: () };

    // EXTI lines 0, 1, 3, 4, 5 from port B. E-stop and limits: NC switches to GND, so
    // opening (rising edge) is the event; both edges are taken so that releasing is
    // seen too, and feed hold likewise. Cycle start acts on pressing (falling edge).
    // The same register values as the HAL's per-pin ExtiPin calls, in one write each.
    const LINES: u32 = (1 << 0) | (1 << 1) | (1 << 3) | (1 << 4) | (1 << 5);
    const PORT_B: u32 = 1;
    // SAFETY: AFIO's clock is on (`constrain`); these EXTICR fields, trigger and mask
    // bits belong to the lines above, which nothing else configures.
    unsafe {
        let afio_regs = &*pac::AFIO::ptr();
        afio_regs
            .exticr1()
            .modify(|r, w| w.bits((r.bits() & !0xF0FF) | PORT_B | (PORT_B << 4) | (PORT_B << 12)));
        afio_regs
            .exticr2()
            .modify(|r, w| w.bits((r.bits() & !0x00FF) | PORT_B | (PORT_B << 4)));
    }
    exti.rtsr()
        .modify(|r, w| unsafe { w.bits((r.bits() | LINES) & !(1 << 5)) });
    exti.ftsr()
        .modify(|r, w| unsafe { w.bits(r.bits() | LINES) });
    exti.imr()
        .modify(|r, w| unsafe { w.bits(r.bits() | LINES) });
    let inputs = Inputs { _owned: () };
    // Not busy: the LED (active low) off and the busy output low, as in `PORTS`.
    let indicators = Indicators { _owned: () };

    // LCD on SPI2. The ST7920 samples on the rising edge with the clock idle low.
    let sck = gpiob.pb13.into_alternate_push_pull(&mut gpiob.crh);
    let mosi = gpiob.pb15.into_alternate_push_pull(&mut gpiob.crh);
    let spi = Spi::new(
        dp.SPI2,
        (
            Some(sck),
            None::<gpio::PB14<Input<gpio::Floating>>>,
            Some(mosi),
        ),
        Mode {
            polarity: Polarity::IdleLow,
            phase: Phase::CaptureOnFirstTransition,
        },
        LCD_SPI_HZ.Hz(),
        &mut rcc,
    );
    let lcd_spi = LcdSpi { spi };

    // USB: force a re-enumeration by pulling D+ low briefly (the Blue Pill has a fixed
    // pull-up on D+), then hand the pins to the USB peripheral.
    // PA12 has been driven low since the port setup.
    cortex_m::asm::delay(sysclk_hz / 100);
    // SAFETY: GPIOA's CRH with PA12 back to the floating input the USB pins need
    // (`PA_CRH_USB`); the other pins keep the modes written above.
    unsafe { (*pac::GPIOA::ptr()).crh().write(|w| w.bits(PA_CRH_USB)) };
    let usb_periph = Peripheral {
        usb: dp.USB,
        pin_dm: gpioa.pa11,
        pin_dp: gpioa.pa12,
    };
    let bus: &'static UsbBusAllocator<UsbBusType> = usb.bus.write(UsbBus::new(usb_periph));
    let serial = usb.serial.write(usbd_serial::SerialPort::new_with_store(
        bus,
        [0; 64],
        usbd_serial::DefaultBufferStore::default(),
    ));
    let usb = usb.dev.write(
        UsbDeviceBuilder::new(bus, UsbVidPid(0x16c0, 0x27dd))
            .device_class(usbd_serial::USB_CLASS_CDC)
            .strings(&[StringDescriptors::default()
                .manufacturer("inkstep")
                .product("inkstep pen plotter (Grbl 1.1)")
                .serial_number("INKSTEP")])
            // One language with three short strings cannot exceed the builder's limits.
            .unwrap_or_else(|_| defmt::panic!("usb strings"))
            .build(),
    );

    let watchdog = Watchdog::start(dp.IWDG);

    let flash = SettingsFlash::new(flash);

    Board {
        step_port,
        step_timer,
        servo,
        keypad,
        inputs,
        indicators,
        lcd_spi,
        usb,
        serial,
        watchdog,
        flash,
        sysclk_hz,
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

/// The internal flash as a NOR flash (embedded-storage traits) for the power-loss-safe
/// settings store in the core. Offsets are chip flash offsets (0 = 0x0800_0000), the
/// store's range ([`settings_pages`]) is the settings pages; reads may look
/// anywhere in the 128 KB, writes and erases only inside the settings pages, so a store
/// bug can never overwrite the program.
///
/// Programming stalls instruction fetch from flash for the duration of a write (~50 µs
/// per half-word) or erase (~20 ms per page), so the firmware only saves at rest.
///
/// The controller is driven by register writes, step for step as the HAL's
/// `FlashWriter` with verification on (RM0008 "Flash program and erase"): unlock with
/// the two keys, program half-words with PG or erase pages with PER/AR/STRT, wait for
/// BSY, check PGERR/WRPRTERR, read back, lock again. The HAL's generic version of
/// the same cost twice the flash.
pub struct SettingsFlash {
    /// Owned so that nothing else reaches the flash controller.
    _flash: stm32f1xx_hal::flash::Parts,
}

/// Where the flash is mapped.
const FLASH_BASE: u32 = 0x0800_0000;

impl SettingsFlash {
    const KEY1: u32 = 0x4567_0123;
    const KEY2: u32 = 0xCDEF_89AB;

    fn new(flash: stm32f1xx_hal::flash::Parts) -> Self {
        Self { _flash: flash }
    }

    fn regs(&mut self) -> &pac::flash::RegisterBlock {
        // SAFETY: this struct owns the flash parts, so it alone uses these registers
        // (the HAL's ACR wait-state setting was done at clock setup).
        unsafe { &*pac::FLASH::ptr() }
    }

    fn wait_idle(&mut self) {
        while self.regs().sr().read().bsy().bit_is_set() {}
    }

    fn unlock(&mut self) -> Result<(), FlashError> {
        self.wait_idle();
        let f = self.regs();
        // SAFETY: the key sequence only unlocks FLASH_CR (in this order, or it stays
        // locked until reset).
        unsafe {
            f.keyr().write(|w| w.bits(Self::KEY1));
            f.keyr().write(|w| w.bits(Self::KEY2));
        }
        if f.cr().read().lock().bit_is_set() {
            return Err(FlashError);
        }
        Ok(())
    }

    fn lock(&mut self) -> Result<(), FlashError> {
        self.wait_idle();
        let f = self.regs();
        f.cr().modify(|_, w| w.lock().set_bit());
        if f.cr().read().lock().bit_is_clear() {
            return Err(FlashError);
        }
        Ok(())
    }

    /// Erase the page holding `offset` and check that it reads back blank.
    fn erase_page(&mut self, offset: u32) -> Result<(), FlashError> {
        self.unlock()?;
        let f = self.regs();
        f.cr().modify(|_, w| w.per().set_bit());
        // SAFETY: AR takes any address; the caller checked it is a settings page.
        f.ar().write(|w| unsafe { w.bits(FLASH_BASE + offset) });
        f.cr().modify(|_, w| w.strt().set_bit());
        // BSY rises one cycle after STRT (STM32F10x errata 2.2.8).
        cortex_m::asm::nop();
        self.wait_idle();
        let f = self.regs();
        let sr = f.sr().read();
        f.cr().modify(|_, w| w.per().clear_bit());
        self.lock()?;
        if sr.wrprterr().bit_is_set() {
            self.regs().sr().modify(|_, w| w.wrprterr().set_bit());
            return Err(FlashError);
        }
        let page = (FLASH_BASE + (offset & !(FLASH_PAGE_SIZE - 1))) as *const u16;
        for i in 0..(FLASH_PAGE_SIZE / 2) as usize {
            // SAFETY: a half-word of the page just erased, inside the flash.
            if unsafe { core::ptr::read_volatile(page.add(i)) } != 0xFFFF {
                return Err(FlashError);
            }
        }
        Ok(())
    }

    /// Program one half-word and check it reads back; on failure the flash is locked.
    fn program(&mut self, addr: u32, half: u16) -> Result<(), FlashError> {
        let f = self.regs();
        f.cr().modify(|_, w| w.pg().set_bit());
        self.wait_idle();
        // SAFETY: a half-word of a settings page, with PG set and the flash unlocked.
        unsafe { core::ptr::write_volatile(addr as *mut u16, half) };
        self.wait_idle();
        let f = self.regs();
        f.cr().modify(|_, w| w.pg().clear_bit());
        let ok = if f.sr().read().pgerr().bit_is_set() {
            f.sr().modify(|_, w| w.pgerr().set_bit());
            false
        } else if f.sr().read().wrprterr().bit_is_set() {
            f.sr().modify(|_, w| w.wrprterr().set_bit());
            false
        } else {
            // SAFETY: the half-word just programmed.
            unsafe { core::ptr::read_volatile(addr as *const u16) == half }
        };
        if !ok {
            self.lock()?;
            return Err(FlashError);
        }
        Ok(())
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub struct FlashError;

impl embedded_storage::nor_flash::NorFlashError for FlashError {
    fn kind(&self) -> embedded_storage::nor_flash::NorFlashErrorKind {
        embedded_storage::nor_flash::NorFlashErrorKind::Other
    }
}

impl embedded_storage::nor_flash::ErrorType for SettingsFlash {
    type Error = FlashError;
}

/// `offset..offset + len` lies inside `lo..hi`.
fn within(offset: u32, len: usize, lo: u32, hi: u32) -> bool {
    let Ok(len) = u32::try_from(len) else {
        return false;
    };
    offset >= lo && offset.checked_add(len).is_some_and(|end| end <= hi)
}

impl embedded_storage::nor_flash::ReadNorFlash for SettingsFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        if !within(offset, bytes.len(), 0, FLASH_SIZE) {
            return Err(FlashError);
        }
        // Half-word aligned, as the HAL's reader required.
        if !offset.is_multiple_of(2) {
            return Err(FlashError);
        }
        // SAFETY: inside the 128 KB of flash (checked above), which is always mapped
        // and only changes through `&mut self`.
        let data =
            unsafe { core::slice::from_raw_parts((FLASH_BASE + offset) as *const u8, bytes.len()) };
        bytes.copy_from_slice(data);
        Ok(())
    }
    fn capacity(&self) -> usize {
        FLASH_SIZE as usize
    }
}

impl embedded_storage::nor_flash::NorFlash for SettingsFlash {
    const WRITE_SIZE: usize = 2;
    const ERASE_SIZE: usize = FLASH_PAGE_SIZE as usize;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let pages = settings_pages();
        if from > to || !within(from, (to - from) as usize, pages.start, pages.end) {
            return Err(FlashError);
        }
        // Half-word aligned, every page from `from` up to `to` (as the HAL did).
        if !from.is_multiple_of(2) || !(to - from).is_multiple_of(2) {
            return Err(FlashError);
        }
        let mut page = from;
        while page < to {
            self.erase_page(page)?;
            page += FLASH_PAGE_SIZE;
        }
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let pages = settings_pages();
        if !within(offset, bytes.len(), pages.start, pages.end) {
            return Err(FlashError);
        }
        if !offset.is_multiple_of(2) || !bytes.len().is_multiple_of(2) {
            return Err(FlashError);
        }
        self.unlock()?;
        let mut addr = FLASH_BASE + offset;
        for pair in bytes.chunks_exact(2) {
            self.program(addr, u16::from_le_bytes([pair[0], pair[1]]))?;
            addr += 2;
        }
        self.lock()
    }
}
