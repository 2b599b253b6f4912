//! The step interrupt's glue between the core's [`Executor`] and the step timer and
//! port: shared by the product image and the bring-up image so both run the same path.
//!
//! Timing per step command, one interrupt per step event: in step/dir mode the timer
//! draws the step pulses itself (PWM on TIM2 CH1-CH3, armed one period ahead through
//! the CCR preloads), so a pulse starts exactly when its wait ends. The timer stops at
//! every update event (one-pulse mode) until the interrupt has taken the next command,
//! armed the channels for the end of the new period and written the directions; then
//! it restarts the timer on schedule (see `board::StepTimer::restart`). So a late
//! interrupt can only delay a step, never repeat one: an armed pulse fires once, at the
//! update event, and no further update comes until the interrupt has run. A pulse
//! lasts the set width, or until the restart if the interrupt comes later than that. A direction pin never changes inside a pulse of its
//! axis: such a change (a reversal) first runs the executor's short turn guard period
//! (pulse width + hold time), at whose end the pin turns. In 4-phase mode the pins are GPIO and the interrupt writes the coil pattern. After the
//! last command the timer runs one more short period so that the last pulse ends. A
//! software pend while the timer is stopped starts it.
//!
//! The executor and the queue's consumer are shared with the preparation side: the
//! interrupt uses them without a lock (it is their highest-priority user), the tasks
//! through short critical sections (position reads, flush on abort, re-zeroing at
//! rest). The command queue is the core's `StepQueue` (on its one SPSC ring).

use crate::board::{self, StepPort, StepTimer};
use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicU32, Ordering};
use inkstep_core::halt::HaltLatch;
use inkstep_core::interpolation::StepEvent;
use inkstep_core::motion::StepPos;
use inkstep_core::pipeline::StepSide;
use inkstep_core::stepper::exec::Executor;
use inkstep_core::stepper::output::OutputConfig;
use inkstep_core::stepper::phase4::Phase4;
use inkstep_core::stepper::queue::{QueueRx, QueueTx, STEP_QUEUE_LEN};
use inkstep_core::stepper::tail_period;

/// The interrupt's whole configuration in one word, so that it costs one load per
/// interrupt: bits 0-2 step invert mask, bits 3-5 direction invert mask, bit 6 4-phase
/// output (written by [`set_output_config`]).
static STEP_STATE: AtomicU32 = AtomicU32::new(0);
/// The core's halt latch: tripped by the e-stop and limit interrupts, looked at by the
/// step interrupt, released by the protocol task ([`release_halt`]).
pub static HALT: HaltLatch = HaltLatch::new();
/// Step pulse width in timer counts (`$0`), taken when the timer starts.
static PULSE_COUNTS: AtomicU32 = AtomicU32::new(720);
/// The executor's reversal guard in timer counts, taken when the timer starts.
static TURN_GUARD_COUNTS: AtomicU32 = AtomicU32::new(0);

const CFG_FOUR_PHASE: u32 = 1 << 6;

/// [`HALT`] was tripped (the e-stop, an armed hard limit): stop the step timer at once
/// (no update event, so no further pulse) and pend the step interrupt, which halts the
/// executor and emits nothing until the latch is released. Any context. (The e-stop
/// turns the drivers off too, through `board::emergency_outputs_off`; an armed hard
/// limit leaves them on to hold the position.)
pub fn halt() {
    board::stop_step_timer();
    cortex_m::peripheral::NVIC::pend(stm32f1xx_hal::pac::Interrupt::TIM2);
}

/// Whether the halt latch is set.
pub fn is_halted() -> bool {
    HALT.is_halted()
}

/// Release the halt latch if the core's rule allows it (`machine_allows`, with the
/// pins read inside), and turn the drivers back on (an e-stop turned them off). With
/// interrupts off, so that an e-stop cannot fall between the pin read and the pin
/// write and be undone.
pub fn release_halt(machine_allows: impl FnOnce() -> bool) {
    cortex_m::interrupt::free(|_| {
        if HALT.is_halted() && HALT.release(machine_allows()) {
            board::drivers_enabled(true);
        }
    });
}

/// The drivers on, unless a halt holds them off: after the enable polarity (`$4`)
/// changed. Interrupts off, like [`release_halt`].
pub fn drivers_on_unless_halted() {
    cortex_m::interrupt::free(|_| {
        if !is_halted() {
            board::drivers_enabled(true);
        }
    });
}

/// The preparation side's end of the queue.
pub type StepTx = QueueTx<'static, STEP_QUEUE_LEN>;
/// The interrupt's end of the queue.
pub type StepRx = QueueRx<'static, STEP_QUEUE_LEN>;

/// Publish the output configuration (at boot and whenever the settings change). The
/// step interrupt applies it to the timer and pins at rest; the pend makes that happen
/// now if the machine is idle.
pub fn set_output_config(cfg: &OutputConfig) {
    PULSE_COUNTS.store(cfg.pulse_ticks, Ordering::Relaxed);
    TURN_GUARD_COUNTS.store(cfg.turn_guard_ticks(), Ordering::Relaxed);
    let word = u32::from(cfg.step_invert & 0b111)
        | (u32::from(cfg.dir_invert & 0b111) << 3)
        | if cfg.four_phase { CFG_FOUR_PHASE } else { 0 };
    STEP_STATE.store(word, Ordering::SeqCst);
    cortex_m::peripheral::NVIC::pend(stm32f1xx_hal::pac::Interrupt::TIM2);
}

/// What the step interrupt consumes.
pub struct Stepper {
    pub exec: Executor,
    pub rx: StepRx,
}

/// The interrupt side's state.
///
/// Access rule: the step interrupt (TIM2) is the highest-priority context that touches
/// it and uses it directly, without a lock, so its path stays short; every other
/// access ([`with_stepper`], [`install`]) runs inside a critical section, during which
/// the step interrupt cannot run. So there is never more than one reference at a time.
struct StepperCell(UnsafeCell<Option<Stepper>>);
// SAFETY: see the access rule above (single core, one lock-free accessor that nothing
// else preempts, every other accessor with interrupts disabled).
unsafe impl Sync for StepperCell {}
static STEPPER: StepperCell = StepperCell(UnsafeCell::new(None));

/// Install the interrupt side (in `init`, before the step interrupt can run) and hand
/// out the step interrupt's output state, which points at it.
pub fn install(exec: Executor, rx: StepRx, port: StepPort, timer: StepTimer) -> StepOutput {
    // SAFETY: interrupts are off inside the critical section (access rule). The pointer
    // stays valid: STEPPER is a static and a later install overwrites it in place.
    let stepper = critical_section::with(|_| unsafe {
        let cell = &mut *STEPPER.0.get();
        core::ptr::from_mut(cell.insert(Stepper { exec, rx }))
    });
    StepOutput {
        port,
        timer,
        stepper,
        phase4: Phase4::default(),
        dir_words: [0; 8],
        applied_cfg: u32::MAX,
    }
}

/// Run `f` on the stepper state with interrupts disabled (tasks only, never the step
/// interrupt itself).
fn with_stepper<R>(f: impl FnOnce(&mut Stepper) -> R) -> Option<R> {
    critical_section::with(|_| {
        // SAFETY: interrupts are off (access rule), and `f` cannot reach STEPPER again.
        unsafe { (*STEPPER.0.get()).as_mut().map(f) }
    })
}

/// The executor's position: every step emitted so far.
pub fn position() -> StepPos {
    with_stepper(|s| s.exec.position()).unwrap_or([0; 3])
}

/// The pipeline's view of the interrupt side on the board.
pub struct BoardSide {
    pub tx: StepTx,
}

impl StepSide for BoardSide {
    type Queue = StepTx;
    fn sink(&mut self) -> &mut Self::Queue {
        &mut self.tx
    }
    fn position(&self) -> StepPos {
        position()
    }
    fn is_running(&self) -> bool {
        // Commands queued answer it without the critical section (which holds the
        // step interrupt back).
        !self.tx.is_empty() || with_stepper(|s| s.exec.is_running()).unwrap_or(false)
    }
    fn queued(&self) -> usize {
        self.tx.len()
    }
    fn flush(&mut self) {
        with_stepper(|s| {
            s.exec.halt();
            s.rx.clear();
            board::disarm_step_pulses();
            HALT.flushed();
        });
    }
    fn set_position(&mut self, p: StepPos) {
        with_stepper(|s| s.exec.set_position(p));
    }
    fn start_now(&mut self, now_ms: u32) {
        // The step interrupt, above the preparation, starts the lead at once.
        kick_since(crate::service_tick::ticks_since_tick(now_ms));
    }
}

/// The interrupt-owned output state (from [`install`]).
pub struct StepOutput {
    pub port: StepPort,
    pub timer: StepTimer,
    /// The installed stepper state (in STEPPER), reached without a `None` check.
    stepper: *mut Stepper,
    phase4: Phase4,
    /// GPIOA BSRR word that outputs each direction state (inversion applied).
    dir_words: [u32; 8],
    /// The output configuration the timer and pins are set up for.
    applied_cfg: u32,
}

// SAFETY: `stepper` points into the STEPPER static, whose access rule does not depend
// on the thread: moving StepOutput from `init` into the step interrupt is fine.
unsafe impl Send for StepOutput {}

impl StepOutput {
    /// The whole TIM2 interrupt. Call it only from the step interrupt (see
    /// `StepperCell`'s access rule): it reads the stepper state without a lock.
    ///
    /// Update event (a period ends): in step/dir mode the timer has just started the
    /// pulses armed for this moment by the previous interrupt, and stopped; the
    /// executor counts them and takes the next command (a reversal of an axis whose
    /// pulse is in flight first runs the executor's turn guard period), and this arms
    /// the channels that pulse when the new period ends, writes the directions and
    /// restarts the timer for the new period. In 4-phase mode the coils are written
    /// here.
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        if !self.timer.take_update() {
            if HALT.is_halted() {
                // SAFETY: as below.
                let st = unsafe { &mut *self.stepper };
                self.halt_now(st);
            } else {
                self.pend(STEP_STATE.load(Ordering::Relaxed));
            }
            return;
        }
        // An update that came before a halt counts the pulse that did start; the halt
        // is looked at before the timer restarts (below).
        // SAFETY: the step interrupt is the lock-free accessor of the access rule, and
        // `stepper` points at the installed state.
        let st = unsafe { &mut *self.stepper };
        let out = st.exec.on_interrupt(&mut st.rx);
        // The output configuration only changes at rest (see `pend`).
        if self.applied_cfg & CFG_FOUR_PHASE != 0 {
            if out.step != 0 {
                let coils = self.phase4.step(StepEvent(out.tick));
                let bits = (coils[0] & 0x0F) | ((coils[1] & 0x0F) << 4);
                self.port.write(bits, !bits);
            }
        } else {
            self.timer.arm_pulses(out.arm);
        }
        if out.dir_changed != 0 {
            self.write_dirs(out.dir);
        }
        let ticks = if out.reload != 0 {
            out.reload
        } else if out.step != 0 {
            // Queue empty: one more short period so that the last pulse still ends.
            tail_period(self.timer.pulse_ticks())
        } else {
            // That period is over (or the queue ran dry after a pure wait): no pulse
            // is in flight, and the timer stopped itself at the update event. When:
            // a start after it may not begin its first period earlier (`pend`).
            STOPPED_AT.store(crate::service_tick::stamp(), Ordering::Relaxed);
            return;
        };
        self.timer.restart(ticks);
        // A halt that came while this ran stopped a timer that was not yet running:
        // stop it again (a halt after the restart stopped it itself, before any
        // update: the period cannot end within these few instructions).
        if HALT.is_halted() {
            self.halt_now(st);
        }
    }

    /// Output direction pins `dir` (bit i set = axis i negative, before inversion).
    #[inline(always)]
    fn write_dirs(&mut self, dir: u8) {
        self.port
            .write_word(self.dir_words[usize::from(dir & 0b111)]);
    }

    /// A software pend with the output not halted (the preparation task's kick, a new
    /// output configuration): start the timer if it is idle and commands wait.
    ///
    /// This and [`StepOutput::halt_now`] are kept out of line for speed: the update event
    /// path, taken once per step, costs 3 instructions less at worst (99 against 102
    /// when measured; bench/isr-cost/run, "step interrupt (update event ...)").
    #[inline(never)]
    fn pend(&mut self, cfg: u32) {
        // SAFETY: as in `on_interrupt`.
        let st = unsafe { &mut *self.stepper };
        if self.timer.is_running() {
            return;
        }
        let four_phase = cfg & CFG_FOUR_PHASE != 0;
        if cfg != self.applied_cfg {
            // At rest: the output mode or polarity changed (or first run).
            self.applied_cfg = cfg;
            self.timer
                .configure_outputs(!four_phase, (cfg & 0b111) as u8);
            // In 4-phase mode PA3-PA5 are coils: the direction words do nothing (a
            // BSRR word of 0 changes no pin).
            for (dir, word) in (0u8..).zip(self.dir_words.iter_mut()) {
                let d = (dir ^ (cfg >> 3) as u8) & 0b111;
                *word = if four_phase {
                    0
                } else {
                    board::bsrr_word(d << board::DIR_SHIFT, (!d & 0b111) << board::DIR_SHIFT)
                };
            }
        }
        // Both from the core's OutputConfig: the pulse fits the 16-bit compare, and
        // 4-phase outputs (levels) have no guard.
        let pulse = PULSE_COUNTS.load(Ordering::Relaxed);
        if pulse != self.timer.pulse_ticks() {
            self.timer.set_pulse_ticks(pulse as u16);
        }
        st.exec
            .set_turn_guard(TURN_GUARD_COUNTS.load(Ordering::Relaxed));
        if let Some(out) = st.exec.start(&mut st.rx) {
            // Directions first (no pulse is in flight); the first pulse comes when
            // the first wait ends.
            self.write_dirs(out.dir);
            if !four_phase {
                self.timer.arm_pulses(out.arm);
            }
            // The first period runs from the service tick whose preparation queued
            // it, as on the simulator's timeline, but never from before the last
            // period's end: a preparation that took longer than the queue lasted
            // (the step queue ran dry in the middle of it, under the pessimistic
            // cycle model) would otherwise start it from its own tick, before the last
            // step, and put the next step out early (seed 1165205060: 35 µs after the
            // one before instead of 481).
            // That is a late start too, counted as one.
            let idle =
                crate::service_tick::stamp().wrapping_sub(STOPPED_AT.load(Ordering::Relaxed));
            let since = KICK_SINCE.swap(0, Ordering::Relaxed);
            if since > idle {
                board::count_late_step_arming();
            }
            // Armed pins: a step comes when this period ends (else it is a part of
            // a longer wait, or a wait with no step).
            self.timer.start(out.reload, since.min(idle), out.arm != 0);
        }
    }

    /// Halted: stop the timer at once, outputs idle, and the executor.
    #[inline(never)]
    fn halt_now(&mut self, st: &mut Stepper) {
        st.exec.halt();
        self.timer.stop_now();
    }
}

/// Step-timer ticks from the service tick whose preparation queued the commands to
/// the kick that starts them ([`kick_since`]): a start from rest runs its first period
/// from that tick, as the simulator does, so that the steps keep the simulator's times
/// whatever the preparation's latency (see `Pipeline::fill_at`).
static KICK_SINCE: AtomicU32 = AtomicU32::new(0);

/// When the step timer last stopped with its queue run dry, on the service tick's
/// clock (`service_tick::stamp`): a start may not reach back before it.
static STOPPED_AT: AtomicU32 = AtomicU32::new(0);

/// Ask the step interrupt to start if commands wait (it ignores the pend if running).
pub fn kick() {
    kick_since(0);
}

/// [`kick`], for commands that the preparation of the service tick `since` ticks ago
/// queued.
pub fn kick_since(since: u32) {
    if !is_halted() {
        KICK_SINCE.store(since, Ordering::Relaxed);
        cortex_m::peripheral::NVIC::pend(stm32f1xx_hal::pac::Interrupt::TIM2);
    }
}
