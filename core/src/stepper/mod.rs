//! Step generation: the segment-preparation task turns planned blocks into timed step
//! commands ([`prep`]), an SPSC queue carries them, and the step-timer interrupt
//! executes them ([`exec`]) with a handful of integer operations per step.
//!
//! Owns the command format shared by both sides and the queue traits that let the
//! same code run on the firmware's lock-free `heapless::spsc` halves and on a plain
//! queue in the simulator and tests; [`queue`] is the lean ring the firmware uses. [`phase4`] maps steps to the 28BYJ-48 half-step
//! sequence; [`drive`] runs the whole chain in virtual time.

pub mod drive;
pub mod exec;
pub mod phase4;
pub mod prep;
pub mod queue;

use crate::interpolation::Tick;
use heapless::spsc::{Consumer, Producer, Queue};

/// Largest wait one command can carry (24 bits of timer ticks).
pub const MAX_WAIT: u32 = (1 << 24) - 1;

/// One step command: wait `wait()` timer ticks after the previous command's step,
/// then emit `tick()`. A tick with no step bits is a pure wait (long pauses).
/// Packed in a u32 so the queue stays small (4 bytes per step). Only [`StepCmd::new`]
/// builds one, so every command's wait is in 2..=MAX_WAIT and its tick in 0..64.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepCmd(pub(crate) u32);

impl StepCmd {
    /// `wait` is clamped to 2..=MAX_WAIT (one tick is 14 ns; the executor promises
    /// every timer reload is at least 2).
    pub fn new(tick: Tick, wait: u32) -> Self {
        StepCmd((u32::from(tick.0 & 0x3f) << 24) | wait.clamp(2, MAX_WAIT))
    }
    #[inline(always)]
    pub fn wait(self) -> u32 {
        self.0 & MAX_WAIT
    }
    #[inline(always)]
    pub fn tick(self) -> Tick {
        // The mask is free (one bit-field extract) and tells the compiler the tick's
        // range, which spares the interrupt two more masks downstream.
        Tick(((self.0 >> 24) & 0x3f) as u8)
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

impl<const N: usize> CmdSink for Queue<StepCmd, N> {
    fn room(&self) -> usize {
        self.capacity() - self.len()
    }
    fn push_slice(&mut self, cmds: &[StepCmd]) -> usize {
        cmds.iter().take_while(|&&c| self.enqueue(c).is_ok()).count()
    }
}

impl<const N: usize> CmdSource for Queue<StepCmd, N> {
    fn pop(&mut self) -> Option<StepCmd> {
        self.dequeue()
    }
}

impl CmdSink for Producer<'_, StepCmd> {
    fn room(&self) -> usize {
        self.capacity() - self.len()
    }
    fn push_slice(&mut self, cmds: &[StepCmd]) -> usize {
        cmds.iter().take_while(|&&c| self.enqueue(c).is_ok()).count()
    }
}

impl CmdSource for Consumer<'_, StepCmd> {
    #[inline(always)]
    fn pop(&mut self) -> Option<StepCmd> {
        self.dequeue()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_packing_round_trips() {
        let t = Tick::from_deltas([1, -1, 0]);
        let c = StepCmd::new(t, 123_456);
        assert_eq!(c.tick(), t);
        assert_eq!(c.wait(), 123_456);
        assert_eq!(StepCmd::new(t, 0).wait(), 2);
        assert_eq!(StepCmd::new(t, u32::MAX).wait(), MAX_WAIT);
    }
}
