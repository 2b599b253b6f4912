//! The step interrupt's glue between the core's [`Executor`] and the step timer and
//! port: shared by the product image and the bring-up image so both run the same path.
//!
//! Timing per step command: the update event emits the step pulses of the command
//! whose wait just ended and programs the next wait; the compare event (one pulse
//! width later) ends the pulses and only then sets the direction pins for the next
//! command, so a direction change never falls inside a pulse and always has the whole
//! wait as set-up time. After the last command the timer runs one more short period so
//! that the last pulse still ends. A software pend while the timer is stopped starts it.
//!
//! The executor and the queue's consumer are shared with the preparation side: the
//! interrupt uses them without a lock (it is their highest-priority user), the tasks
//! through short critical sections (position reads, flush on abort, re-zeroing at
//! rest). The command queue is the core's lean [`StepQueue`] ring.

use crate::board::{self, StepPort, StepTimer};
use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use inkstep_core::interp::Tick;
use inkstep_core::link::StepSide;
use inkstep_core::motion::StepPos;
use inkstep_core::stepper::exec::Executor;
use inkstep_core::stepper::phase4::Phase4;
use inkstep_core::stepper::queue::{QueueRx, QueueTx, StepQueue};

/// Latched by the e-stop (and an armed hard limit): the step interrupt halts the
/// executor and emits nothing until the machine is reset.
pub static HALT: AtomicBool = AtomicBool::new(false);
/// Output configuration for the interrupt, one word so it costs one load per
/// interrupt: bits 0-2 step invert mask, bits 3-5 direction invert mask, bit 6
/// 4-phase output. Written by [`set_output_config`].
static OUTPUT_CONFIG: AtomicU32 = AtomicU32::new(0);
/// Step pulse width in timer ticks (`$0`), taken when the timer starts.
pub static PULSE_TICKS: AtomicU32 = AtomicU32::new(720);

const CFG_FOUR_PHASE: u32 = 1 << 6;

/// Step commands the queue holds (4 bytes each): 256 is several milliseconds of
/// stepping at the highest rates, enough to ride out the lower-priority tasks.
pub const STEP_QUEUE_LEN: usize = 256;
/// The queue's storage type, for a `static` or an RTIC local.
pub type StepCmdQueue = StepQueue<STEP_QUEUE_LEN>;
/// The preparation side's end of the queue.
pub type StepTx = QueueTx<'static, STEP_QUEUE_LEN>;
/// The interrupt's end of the queue.
pub type StepRx = QueueRx<'static, STEP_QUEUE_LEN>;

/// Publish the output configuration (at boot and whenever the settings change).
pub fn set_output_config(step_invert: u8, dir_invert: u8, four_phase: bool) {
    let word = u32::from(step_invert & 0b111)
        | (u32::from(dir_invert & 0b111) << 3)
        | if four_phase { CFG_FOUR_PHASE } else { 0 };
    OUTPUT_CONFIG.store(word, Ordering::Relaxed);
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

/// Install the interrupt side (once, in `init`).
pub fn install(exec: Executor, rx: StepRx) {
    // SAFETY: interrupts are off inside the critical section (access rule).
    critical_section::with(|_| unsafe { *STEPPER.0.get() = Some(Stepper { exec, rx }) });
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

/// The link's view of the interrupt side on the board.
pub struct BoardSide {
    pub tx: StepTx,
}

impl StepSide for BoardSide {
    type Sink = StepTx;
    fn sink(&mut self) -> &mut Self::Sink {
        &mut self.tx
    }
    fn position(&self) -> StepPos {
        position()
    }
    fn is_running(&self) -> bool {
        with_stepper(|s| s.exec.is_running()).unwrap_or(false) || !self.tx.is_empty()
    }
    fn queued(&self) -> usize {
        self.tx.len()
    }
    fn flush(&mut self) {
        with_stepper(|s| {
            s.exec.halt();
            s.rx.clear();
            s.exec.reset();
        });
    }
    fn set_position(&mut self, p: StepPos) {
        with_stepper(|s| s.exec.set_position(p));
    }
}

/// The interrupt-owned output state.
pub struct StepOutput {
    pub port: StepPort,
    pub timer: StepTimer,
    phase4: Phase4,
    /// Direction pins to output when the running pulse ends.
    next_dir: u8,
    /// The last command has run; this period only lets its pulse end.
    finishing: bool,
}

impl StepOutput {
    pub fn new(port: StepPort, timer: StepTimer) -> Self {
        Self {
            port,
            timer,
            phase4: Phase4::default(),
            next_dir: 0,
            finishing: false,
        }
    }

    /// The whole TIM2 interrupt. Call it only from the step interrupt (see
    /// [`StepperCell`]'s access rule): it reads the stepper state without a lock.
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        let events = self.timer.take_events();
        let cfg = OUTPUT_CONFIG.load(Ordering::Relaxed);
        let step_inv = (cfg & 0b111) as u8;
        if events & board::EVENT_UPDATE == 0 {
            if events & board::EVENT_COMPARE != 0 {
                self.pulse_end(cfg, step_inv);
            } else {
                // A software pend: the preparation task's kick or the e-stop.
                self.start(cfg);
            }
            return;
        }
        // SAFETY: the step interrupt is the lock-free accessor of the access rule.
        let Some(st) = (unsafe { &mut *STEPPER.0.get() }).as_mut() else {
            return;
        };
        if HALT.load(Ordering::Relaxed) || core::mem::take(&mut self.finishing) {
            self.stop(st);
            return;
        }
        let out = st.exec.on_interrupt(&mut st.rx);
        if out.step != 0 {
            if cfg & CFG_FOUR_PHASE != 0 {
                let coils = self.phase4.step(Tick(out.step | (out.dir << 3)));
                let bits = (coils[0] & 0x0F) | ((coils[1] & 0x0F) << 4);
                self.port.write(bits, !bits);
            } else {
                self.port.write(out.step ^ step_inv, out.step & step_inv);
            }
        }
        self.next_dir = out.dir;
        if out.reload == 0 {
            // Queue empty: one more short period so that the last pulse still ends.
            self.finishing = true;
            self.timer
                .set_period((2 * self.timer.pulse_ticks() + 16).min(0x1_0000));
        } else {
            self.timer.set_period(out.reload);
        }
    }

    /// Compare event, one pulse width after the update: step pins back to idle, then
    /// the next command's directions.
    #[inline(always)]
    fn pulse_end(&mut self, cfg: u32, step_inv: u8) {
        if cfg & CFG_FOUR_PHASE == 0 {
            let dir = (self.next_dir ^ (cfg >> 3) as u8) & 0b111;
            let set = dir << board::DIR_SHIFT;
            let clear = (!dir & 0b111) << board::DIR_SHIFT;
            // The idle level of a step pin is its inverted level.
            self.port.write(step_inv | set, (!step_inv & 0b111) | clear);
        }
    }

    /// Halted, or the last pulse has ended: stop the timer.
    #[inline(always)]
    fn stop(&mut self, st: &mut Stepper) {
        if HALT.load(Ordering::Relaxed) {
            st.exec.halt();
        }
        self.timer.stop();
    }

    /// A pend while the timer may be stopped: start it if commands wait.
    #[inline(never)]
    fn start(&mut self, cfg: u32) {
        // SAFETY: the step interrupt is the lock-free accessor of the access rule.
        let Some(st) = (unsafe { &mut *STEPPER.0.get() }).as_mut() else {
            return;
        };
        if HALT.load(Ordering::Relaxed) {
            self.stop(st);
            return;
        }
        if self.timer.is_running() {
            return;
        }
        if let Some(out) = st.exec.start(&mut st.rx) {
            // Direction first; the first pulse comes one wait later.
            self.next_dir = out.dir;
            let d = (out.dir ^ (cfg >> 3) as u8) & 0b111;
            self.port
                .write(d << board::DIR_SHIFT, (!d & 0b111) << board::DIR_SHIFT);
            let pulse = PULSE_TICKS.load(Ordering::Relaxed).clamp(1, 0xFFFF);
            self.timer.set_pulse_ticks(pulse as u16);
            self.timer.set_period(out.reload);
            self.timer.start();
        }
    }
}

/// Ask the step interrupt to start if commands wait (it ignores the pend if running).
pub fn kick() {
    if !HALT.load(Ordering::Relaxed) {
        cortex_m::peripheral::NVIC::pend(stm32f1xx_hal::pac::Interrupt::TIM2);
    }
}
