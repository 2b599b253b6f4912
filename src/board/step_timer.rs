//! TIM2, the step timer: it draws the step pulses itself in step/dir mode (PWM on
//! CH1-CH3, armed one period ahead) and raises one interrupt per step event; and TIM3,
//! its clock.
//!
//! TIM2 runs in one-pulse mode: its counter stops at every update event, so a period
//! whose interrupt has not yet come cannot be repeated (the free-running timer this
//! replaces drew the previous period's pulses again when the interrupt came more than
//! a period late: a step the firmware never counted, issue 20). The interrupt restarts
//! it on schedule: TIM3 counts freely at half the step timer's rate, the schedule (when
//! each period is due to end) is kept in its time, and the counter starts at the ticks
//! already gone since the scheduled start of the new period, so that it ends on time
//! whatever the interrupt's latency (the restart's own few instructions from the clock
//! read to the counter's start count against the schedule's beginning, which a start
//! from rest reads the same way). An interrupt too late to keep the schedule starts a
//! short period instead: the step comes late, never twice, the schedule moves with it,
//! and the late arming is counted ([`LATE_STEP_ARMINGS`]).

use super::{STEP_TIMER_HZ, SYSCLK_HZ};
use core::sync::atomic::{AtomicU32, Ordering};
use inkstep_core::stepper::output::DIR_HOLD_COUNTS;
use inkstep_core::stepper::MAX_RELOAD;
use stm32f1xx_hal::pac;

/// The update event flag (UIF): a period has ended.
const EVENT_UPDATE: u32 = 1;

/// TIM2 CR1 while running: CEN, URS (only overflows raise the update interrupt, not
/// UG), OPM (the counter stops at the update event). No ARR preload: the reload
/// written before each restart is the length of the period it starts.
const CR1_RUN: u32 = 0b1101;
/// TIM2 CR1 while stopped.
const CR1_STOPPED: u32 = 0b1100;
/// TIM3 counts every second step-timer count (prescaler 2): 2^17 ticks, 1.8 ms, go
/// round its 16 bits, twice the longest step period, so that a lateness up to that
/// reads unambiguously.
const CLOCK_SHIFT: u32 = 1;
/// The schedule's times are step-timer counts modulo 2^17 (TIM3's count, doubled).
const CLOCK_MASK: u32 = (0x1_0000 << CLOCK_SHIFT) - 1;
/// How far behind its schedule a start may leave the restart after it (`start`): the
/// restart reads a lateness up to half the clock's round (0.91 ms); a quarter of that
/// is kept for the restart's own latency (the longest masked section, a defmt log
/// line, is about 35 µs; the USB driver's packet copies no longer mask it).
const LATE_REACH: u32 = CLOCK_MASK / 2 - CLOCK_MASK / 8;
/// How much longer [`StepTimer::restart`] takes from its clock read to the counter's
/// start than [`StepTimer::start`] does: 4 instructions (9 against 5 in the release
/// image) at one cycle each, the least they can take. The schedule begins at the start's
/// clock read, and every restart's own delay then counts against it, so only this
/// difference matters: an error in it moves every step after the start by as many
/// ticks, the same for all of them (an underestimate later, never earlier).
const RESTART_LEAD: u32 = 4;
/// The shortest rest of a period after a late restart: the low time before the next
/// pulse and the direction hold after a pulse that the lateness stretched.
const MIN_LATE_COUNTS: u32 = DIR_HOLD_COUNTS;

/// Step interrupts that came too late to start their period on schedule since
/// power-up: each delayed a step (or a wait) by its lateness, none added or lost one.
/// Written only by the step interrupt; read by the tasks (the log) and, under its
/// exported name, by the emulator's rate trials.
#[export_name = "inkstep_late_step_armings"]
pub static LATE_STEP_ARMINGS: AtomicU32 = AtomicU32::new(0);

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
    /// TIM3, the schedule's clock: free-running, one count per two ticks.
    clock: pac::TIM3,
    /// When the running period is due to end, in ticks on the clock (modulo 2^17) as
    /// a restart reads it (see `RESTART_LEAD`): the ticks gone at a restart are one
    /// subtraction.
    due_early: u32,
    /// Pulse width in ticks, the CCR value of an armed channel.
    pulse: u32,
    /// CCR1-CCR3 for each step mask (bit i = axis i): `pulse` or 0 (a fourth word
    /// pads each row to 16 bytes, so the interrupt indexes it with one shift).
    arm_table: [[u32; 4]; 8],
}

impl StepTimer {
    pub(super) fn new(tim: pac::TIM2, clock: pac::TIM3) -> Self {
        // SAFETY: enabling the TIM2 and TIM3 clocks; RCC is otherwise owned by the HAL
        // but these bits are not touched by it after freeze.
        unsafe {
            let rcc = &*pac::RCC::ptr();
            rcc.apb1enr()
                .modify(|_, w| w.tim2en().set_bit().tim3en().set_bit());
            rcc.apb1rstr()
                .modify(|_, w| w.tim2rst().set_bit().tim3rst().set_bit());
            rcc.apb1rstr()
                .modify(|_, w| w.tim2rst().clear_bit().tim3rst().clear_bit());
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
            tim.cr1().write(|w| w.bits(CR1_STOPPED));
            tim.dier().write(|w| w.bits(DIER_UPDATE));
            // The clock: free-running over 16 bits, no interrupt.
            clock.psc().write(|w| w.bits((1 << CLOCK_SHIFT) - 1));
            clock.arr().write(|w| w.bits(0xFFFF));
            clock.egr().write(|w| w.ug().set_bit());
            clock.sr().write(|w| w.bits(0));
            clock.cr1().write(|w| w.cen().set_bit());
        }
        let mut t = Self {
            tim,
            clock,
            due_early: 0,
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

    /// Set the pulse width in timer counts (at rest; taken by the next armed pulse).
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

    /// The clock's time in ticks (modulo 2^17).
    #[inline(always)]
    fn now(&self) -> u32 {
        self.clock.cnt().read().bits() << CLOCK_SHIFT
    }

    /// Start the period that began at the update event just taken, `ticks` long
    /// (2..=65536, which the core's executor guarantees), on schedule: with the counter
    /// started at the ticks already gone since the period's scheduled start (the last
    /// one's scheduled end), so that it ends `ticks` after that whatever the
    /// interrupt's latency; or, if that is too late to leave 1 µs (`MIN_LATE_COUNTS`) of
    /// it, as that short rest from now (counted in `LATE_STEP_ARMINGS`).
    #[inline(always)]
    pub fn restart(&mut self, ticks: u32) {
        debug_assert!((2..=MAX_RELOAD).contains(&ticks));
        // SAFETY: any 16-bit auto-reload; `ticks` is 2..=0x10000. The counter is
        // stopped (one-pulse mode).
        self.tim
            .arr()
            .write(|w| unsafe { w.bits(ticks.wrapping_sub(1)) });
        let due_early = self.due_early;
        // From the clock's read to the counter's start with interrupts masked (a few
        // instructions): a handler above this one (SysTick, the inputs) taken in
        // between started the counter late by its own length, the period ended that
        // much after the schedule, and the next restart, on schedule, cut that
        // pulse by as much (a `$0=10` pulse of 8.1 µs after one of 11.9 µs:
        // emu/tests/pins.rs).
        cortex_m::interrupt::disable();
        let gone = self.now().wrapping_sub(due_early) & CLOCK_MASK;
        if gone + MIN_LATE_COUNTS <= ticks {
            self.run(gone);
            // SAFETY: the step interrupt runs unmasked; it masks only the lines above.
            unsafe { cortex_m::interrupt::enable() };
            self.due_early = due_early.wrapping_add(ticks);
        } else {
            // SAFETY: as above.
            unsafe { cortex_m::interrupt::enable() };
            self.late(gone, ticks);
        }
    }

    /// The restart of an interrupt too late for the schedule: the period's last
    /// [`MIN_LATE_COUNTS`] (or all of it, if shorter) from now, and the schedule moved.
    /// A time past the schedule by more than half the clock's round (0.9 ms) reads as
    /// one before it: the period runs in full from now, uncounted, so that a step can
    /// never come early. (Only a debugger's halt can hold the interrupt that long: the
    /// longest masked section is about 35 µs, and settings are written to flash at
    /// rest.)
    #[inline(never)]
    fn late(&mut self, gone: u32, ticks: u32) {
        let start = if gone > CLOCK_MASK / 2 {
            0
        } else {
            // The step interrupt is the only writer.
            LATE_STEP_ARMINGS.store(
                LATE_STEP_ARMINGS.load(Ordering::Relaxed).wrapping_add(1),
                Ordering::Relaxed,
            );
            ticks.saturating_sub(MIN_LATE_COUNTS)
        };
        self.run(start);
        // The new period began `start` ticks before the restart, `gone` after the old
        // schedule's mark.
        self.due_early = self
            .due_early
            .wrapping_add(gone)
            .wrapping_sub(start)
            .wrapping_add(ticks);
    }

    /// Start the counter at `start` (below the reload written before).
    #[inline(always)]
    fn run(&mut self, start: u32) {
        // SAFETY: any 16-bit count; documented CR1 bits.
        unsafe {
            self.tim.cnt().write(|w| w.bits(start));
            self.tim.cr1().write(|w| w.bits(CR1_RUN));
        }
    }

    /// Start from rest with a first period of `ticks`; the schedule begins now.
    ///
    /// The period began `since` ticks ago (the service tick whose preparation queued
    /// it, on which the simulator starts it too): it ends `ticks` after that, or, if
    /// that leaves less than `MIN_LATE_COUNTS`, that short rest from now. If a step
    /// comes at its end (`step_due`), that is a late arming and the schedule moves.
    /// If not (a part of a long wait; the preparation, an arc's start say, took longer
    /// than this part), the schedule stays the tick's: the next period's restart takes
    /// the rest of the lateness, so the first step still comes on time. That restart
    /// reads at most `LATE_REACH` of it (the clock's half round, less a margin for the
    /// restart's own latency); beyond, the schedule moves, counted as a late arming.
    pub fn start(&mut self, ticks: u32, since: u32, step_due: bool) {
        // SAFETY: any 16-bit auto-reload; `ticks` is 2..=0x10000.
        self.tim
            .arr()
            .write(|w| unsafe { w.bits(ticks.wrapping_sub(1)) });
        // Masked from the clock's read to the counter's start, as in `restart`.
        cortex_m::interrupt::disable();
        let now = self.now();
        let most = ticks.saturating_sub(MIN_LATE_COUNTS);
        let gone = since.min(most);
        let behind = if step_due {
            gone
        } else {
            since.min(most + LATE_REACH)
        };
        if since > behind {
            // The step interrupt is the only writer.
            LATE_STEP_ARMINGS.store(
                LATE_STEP_ARMINGS.load(Ordering::Relaxed).wrapping_add(1),
                Ordering::Relaxed,
            );
        }
        self.run(gone);
        // SAFETY: the step interrupt runs unmasked (this is called from it, for a
        // start from rest); it masks only the lines above.
        unsafe { cortex_m::interrupt::enable() };
        self.due_early = now
            .wrapping_sub(behind)
            .wrapping_add(ticks)
            .wrapping_sub(RESTART_LEAD);
    }

    pub fn stop(&mut self) {
        // SAFETY: documented CR1 bits.
        self.tim.cr1().write(|w| unsafe { w.bits(CR1_STOPPED) });
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
/// store, CEN cleared and URS and OPM kept (StepTimer's configuration).
pub fn stop_step_timer() {
    // SAFETY: a single store to TIM2's CR1.
    unsafe {
        (*pac::TIM2::ptr()).cr1().write(|w| w.bits(CR1_STOPPED));
    }
}

/// Count a late arming found outside the timer (a start that the last stop held
/// back: `steps::StepOutput::pend`). The step interrupt only.
pub fn count_late_step_arming() {
    LATE_STEP_ARMINGS.store(
        LATE_STEP_ARMINGS.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

/// Late step armings since power-up (see `LATE_STEP_ARMINGS`).
pub fn late_step_armings() -> u32 {
    LATE_STEP_ARMINGS.load(Ordering::Relaxed)
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
