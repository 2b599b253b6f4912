//! Step generation: the segment-preparation task turns planned blocks into timed step
//! commands ([`prep`]), a queue on the crate's SPSC ring carries them, and the
//! step-timer interrupt executes them ([`exec`]) with a handful of integer operations
//! per step.
//!
//! Owns the command format shared by both sides, the step timer's constants that the
//! board and the simulator share, and the queue traits; [`queue`] is the ring between
//! preparation and interrupt (the firmware and the simulator run the same one),
//! [`output`] the output configuration both derive from the settings, and [`phase4`]
//! maps steps to the 28BYJ-48 half-step sequence; [`idle`] decides the motors' power
//! at rest (`$1`) and the busy outputs, millisecond by millisecond.

pub mod exec;
pub mod idle;
pub mod output;
pub mod phase4;
pub mod prep;
pub mod queue;

use crate::interpolation::StepEvent;

/// The step timer's clock: the board's TIM2 counts at the 72 MHz core clock, and the
/// simulator's virtual timer at the same rate, so waits are the same numbers of ticks.
pub const TIMER_HZ: u32 = 72_000_000;
/// The longest timer period one reload can program: the board's 16-bit TIM2 is written
/// with `reload - 1`, so 0x10000 ticks (910 us). Longer waits are split by the
/// [`exec::Executor`]; the simulator uses the same limit so that it splits them alike.
pub const MAX_RELOAD: u32 = 0x1_0000;

/// The period the timer runs after the last queued command's steps, so that their
/// pulses (`pulse_ticks` long) end before it stops; the board and the simulator stop
/// their timer when it is over.
#[inline(always)]
pub fn tail_period(pulse_ticks: u32) -> u32 {
    (2 * pulse_ticks + 16).min(MAX_RELOAD)
}

/// The step-event rate (interpolation ticks per second) the planner lets a move ask
/// for: every block's speed is capped so that its events come no faster
/// ([`crate::planner::geometry`]), so a program that asks for more runs slower, and the
/// step queue never runs dry. Measured on the product image in the emulator under its
/// pessimistic cycle model (emu/README.md "Cycle model"; emu/tests/step_rate.rs,
/// docs/performance.md): with realistic lines streaming over USB, `?` polling and the
/// LCD drawing, the counting trials at the cap have no late arming along X or on a
/// diagonal traced point by point. A build with the cap lifted (and `$0=3`) carried
/// lines at up to 105,000 events/s with none; what keeps the cap here is `$0`'s
/// default (10 µs: 83,333 events/s, [`event_rate_for_pulse`]) and programs of short
/// blocks, whose fixed cost per block the preparation pays: bench/isr-cost's sine.nc
/// keeps up with 88,000 events/s only with the whole CPU.
pub const MAX_STEP_RATE: f32 = 80_000.0;

/// The shortest low time a step pin keeps between two pulses, µs: what stepper drivers
/// ask between pulses (A4988 1 µs, DRV8825 1.9 µs), with room for the timing
/// polynomials' error (0.5 µs).
pub const STEP_LOW_US: f32 = 2.0;

/// The step-event rate the step pins can carry with pulses of `pulse_us` (`$0`): every
/// period at least the pulse and [`STEP_LOW_US`] after it, and never above
/// [`MAX_STEP_RATE`]. Longer pulses than a period allows would run into each other on
/// the pin: the driver would see one step where the firmware counted several.
pub fn event_rate_for_pulse(pulse_us: u8) -> f32 {
    MAX_STEP_RATE.min(1e6 / (f32::from(pulse_us) + STEP_LOW_US))
}

/// The step-event rate the planner lets a move whose events are timed one by one ask
/// for (an ellipse, a sine, a circle traced point by point; see
/// `planner::geometry`): each such event costs the preparation a profile evaluation of
/// its own, about 100 µs under the pessimistic cycle model. Measured on the product
/// image (emu/tests/step_rate.rs, an R20 circle point by point and as an ellipse at
/// 1280 steps/mm asking for more): both keep up with the cap at 9,000 events/s; at
/// 10,000 the preparation falls behind, the tasks below it stop running and the
/// watchdog resets the board (at the old common cap of 80,000 it did so within 3,500
/// steps). The cap keeps 22 % below 9,000.
pub const MAX_SINGLE_EVENT_RATE: f32 = 7_000.0;

/// Largest wait one command can carry (24 bits of timer counts).
pub const MAX_WAIT: u32 = (1 << 24) - 1;

/// One step command: wait `wait()` timer counts after the previous command's step,
/// then emit `tick()`. A tick with no step bits is a pure wait (long pauses).
/// Packed in a u32 so the queue stays small (4 bytes per step). Only [`StepCmd::new`]
/// builds one, so every command's wait is in 2..=MAX_WAIT and its tick in 0..64.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepCmd(pub(crate) u32);

impl StepCmd {
    /// `wait` is clamped to 2..=MAX_WAIT (one tick is 14 ns; the executor promises
    /// every timer reload is at least 2).
    pub fn new(tick: StepEvent, wait: u32) -> Self {
        StepCmd((u32::from(tick.0 & 0x3f) << 24) | wait.clamp(2, MAX_WAIT))
    }
    #[inline(always)]
    pub fn wait(self) -> u32 {
        self.0 & MAX_WAIT
    }
    #[inline(always)]
    pub fn tick(self) -> StepEvent {
        // The mask is free (one bit-field extract) and tells the compiler the tick's
        // range, which spares the interrupt two more masks downstream.
        StepEvent(((self.0 >> 24) & 0x3f) as u8)
    }
}

/// Where prepared commands go.
pub trait CmdSink {
    /// Commands that fit now.
    fn room(&self) -> usize;
    /// Appends `cmds` in order, as many as fit (call `room` first): the count taken.
    fn push_slice(&mut self, cmds: &[StepCmd]) -> usize;
}

/// Where the interrupt takes commands from.
pub trait CmdSource {
    fn pop(&mut self) -> Option<StepCmd>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_packing_round_trips() {
        let t = StepEvent::from_deltas([1, -1, 0]);
        let c = StepCmd::new(t, 123_456);
        assert_eq!(c.tick(), t);
        assert_eq!(c.wait(), 123_456);
        assert_eq!(StepCmd::new(t, 0).wait(), 2);
        assert_eq!(StepCmd::new(t, u32::MAX).wait(), MAX_WAIT);
    }
}
