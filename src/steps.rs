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
//! The executor and the queue's consumer are shared with the preparation side through
//! short critical sections (position reads, flush on abort, re-zeroing at rest).

use crate::board::{self, StepPort, StepTimer};
use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use heapless::spsc::{Consumer, Producer};
use inkstep_core::interp::Tick;
use inkstep_core::link::StepSide;
use inkstep_core::motion::StepPos;
use inkstep_core::stepper::exec::Executor;
use inkstep_core::stepper::phase4::Phase4;
use inkstep_core::stepper::StepCmd;

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
    pub rx: Consumer<'static, StepCmd>,
}

/// The interrupt side's state. Only ever touched inside a critical section (the step
/// interrupt's body and [`with_stepper`]), so no borrow flag is needed on top.
struct StepperCell(UnsafeCell<Option<Stepper>>);
// SAFETY: every access happens inside `critical_section::with`, i.e. with interrupts
// disabled on this single-core MCU, so there is never more than one reference.
unsafe impl Sync for StepperCell {}
static STEPPER: StepperCell = StepperCell(UnsafeCell::new(None));

/// Run `f` on the stepper state with interrupts disabled.
#[inline(always)]
fn locked<R>(f: impl FnOnce(&mut Option<Stepper>) -> R) -> R {
    critical_section::with(|_| {
        // SAFETY: interrupts are off (single core), and `f` cannot reach STEPPER again.
        f(unsafe { &mut *STEPPER.0.get() })
    })
}

/// Install the interrupt side (once, in `init`).
pub fn install(exec: Executor, rx: Consumer<'static, StepCmd>) {
    locked(|s| *s = Some(Stepper { exec, rx }));
}

fn with_stepper<R>(f: impl FnOnce(&mut Stepper) -> R) -> Option<R> {
    locked(|s| s.as_mut().map(f))
}

/// The executor's position: every step emitted so far.
pub fn position() -> StepPos {
    with_stepper(|s| s.exec.position()).unwrap_or([0; 3])
}

/// The link's view of the interrupt side on the board.
pub struct BoardSide {
    pub tx: Producer<'static, StepCmd>,
}

impl StepSide for BoardSide {
    type Sink = Producer<'static, StepCmd>;
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
            while s.rx.dequeue().is_some() {}
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

    /// The whole TIM2 interrupt.
    #[inline(always)]
    pub fn on_interrupt(&mut self) {
        let (update, compare) = self.timer.take_events();
        let cfg = OUTPUT_CONFIG.load(Ordering::Relaxed);
        let step_inv = (cfg & 0b111) as u8;
        let four_phase = cfg & CFG_FOUR_PHASE != 0;
        if compare && !update {
            // Pulse end: step pins back to idle, then the next command's directions.
            if !four_phase {
                let dir = (self.next_dir ^ (cfg >> 3) as u8) & 0b111;
                let set = dir << board::DIR_SHIFT;
                let clear = (!dir & 0b111) << board::DIR_SHIFT;
                // The idle level of a step pin is its inverted level.
                self.port.write(step_inv | set, (!step_inv & 0b111) | clear);
            }
            return;
        }
        locked(|st| {
            let Some(st) = st.as_mut() else { return };
            if HALT.load(Ordering::Relaxed) {
                st.exec.halt();
                self.timer.stop();
                return;
            }
            if update && self.timer.is_running() {
                if core::mem::take(&mut self.finishing) {
                    self.timer.stop();
                } else {
                    let out = st.exec.on_interrupt(&mut st.rx);
                    if out.step != 0 {
                        if four_phase {
                            let coils = self.phase4.step(Tick(out.step | (out.dir << 3)));
                            let bits = (coils[0] & 0x0F) | ((coils[1] & 0x0F) << 4);
                            self.port.write(bits, !bits);
                        } else {
                            self.port.write(out.step ^ step_inv, out.step & step_inv);
                        }
                    }
                    self.next_dir = out.dir;
                    if out.reload == 0 {
                        self.finishing = true;
                        self.timer.set_period(2 * self.timer.pulse_ticks() + 16);
                    } else {
                        self.timer.set_period(out.reload);
                    }
                    return;
                }
            }
            if !self.timer.is_running() {
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
        });
    }
}

/// Ask the step interrupt to start if commands wait (it ignores the pend if running).
pub fn kick() {
    if !HALT.load(Ordering::Relaxed) {
        cortex_m::peripheral::NVIC::pend(stm32f1xx_hal::pac::Interrupt::TIM2);
    }
}
