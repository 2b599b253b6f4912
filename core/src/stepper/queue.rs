//! The step-command queue between the segment-preparation task (producer) and the
//! step-timer interrupt (consumer): the crate's one SPSC [`Ring`] of packed
//! [`StepCmd`] words, plus the one thing the step path adds on the way in, sticky
//! direction bits. The interrupt's `pop` is the ring's, inlined: a handful of
//! instructions of a step interrupt that must stay under 100 (bench/isr-cost).

use super::{CmdSink, CmdSource, StepCmd};
use crate::ring::{Ring, Rx, Tx};
use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

/// Step commands the queue holds (4 bytes each): 256 is several milliseconds of
/// stepping at the highest rates, enough to ride out the lower-priority tasks. The
/// firmware and the simulator both use this length.
pub const STEP_QUEUE_LEN: usize = 256;

/// The queue the firmware and the simulator run.
pub type StepCmdQueue = StepQueue<STEP_QUEUE_LEN>;

/// The queue. `N` must be a power of two (checked at compile time by the ring).
pub struct StepQueue<const N: usize> {
    ring: Ring<AtomicU32, N>,
    /// Direction bits as of the last command pushed (bit i = axis i negative; written
    /// by the producer only). Kept in the queue, not in the producer's end, so that an
    /// owner of the whole queue (the simulator) may take the ends anew at each use.
    dirs: AtomicU8,
}

impl<const N: usize> Default for StepQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> StepQueue<N> {
    pub const fn new() -> Self {
        StepQueue {
            ring: Ring::new(),
            dirs: AtomicU8::new(0),
        }
    }

    /// The two ends. Taking `&mut` guarantees one producer and one consumer.
    pub fn split(&mut self) -> (QueueTx<'_, N>, QueueRx<'_, N>) {
        (QueueTx { q: self }, QueueRx { q: self })
    }

    /// Commands waiting.
    pub fn queued(&self) -> usize {
        self.ring.len()
    }

    /// Drops everything queued (abort), as the interrupt's end does.
    pub fn clear(&mut self) {
        self.split().1.clear();
    }
}

/// The producer end (the preparation task).
pub struct QueueTx<'a, const N: usize> {
    q: &'a StepQueue<N>,
}

impl<const N: usize> QueueTx<'_, N> {
    /// The ring's producing end (this is the queue's only producer).
    #[inline(always)]
    fn tx(&self) -> Tx<'_, AtomicU32, N> {
        self.q.ring.producer()
    }
    /// Commands waiting (the consumer may take some meanwhile).
    pub fn len(&self) -> usize {
        N - self.tx().free()
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    pub fn is_full(&self) -> bool {
        self.tx().free() == 0
    }
    /// Appends `c`; false (and nothing written) if the queue is full.
    pub fn push(&mut self, c: StepCmd) -> bool {
        self.push_slice(&[c]) == 1
    }

    /// Appends as many of `cmds` as fit, in order, and publishes them at once: the count
    /// taken.
    ///
    /// Direction bits become sticky on the way in: an axis that does not step in a
    /// command gets the direction it had in the previous one (a tick's direction bit of
    /// a non-stepping axis means nothing), so the interrupt can output the three bits as
    /// they are and a pin still only changes where a step needs it.
    pub fn push_slice(&mut self, cmds: &[StepCmd]) -> usize {
        let mut dirs = self.q.dirs.load(Ordering::Relaxed);
        let taken = self.tx().push_map(cmds, |c| {
            let bits = (c.0 >> 24) as u8;
            let mask = bits & 0b111;
            dirs = (dirs & !mask) | ((bits >> 3) & mask);
            (c.0 & !(0b111 << 27)) | (u32::from(dirs) << 27)
        });
        self.q.dirs.store(dirs, Ordering::Relaxed);
        taken
    }
}

/// The consumer end (the step interrupt).
pub struct QueueRx<'a, const N: usize> {
    q: &'a StepQueue<N>,
}

impl<const N: usize> QueueRx<'_, N> {
    /// The ring's consuming end (this is the queue's only consumer).
    #[inline(always)]
    fn rx(&self) -> Rx<'_, AtomicU32, N> {
        self.q.ring.consumer()
    }
    /// Takes the oldest command.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<StepCmd> {
        self.rx().pop().map(StepCmd)
    }
    /// Drops everything queued (abort); the producer may keep pushing afterwards.
    pub fn clear(&mut self) {
        self.rx().clear();
    }
}

impl<const N: usize> CmdSink for QueueTx<'_, N> {
    fn room(&self) -> usize {
        self.tx().free()
    }
    fn push_slice(&mut self, cmds: &[StepCmd]) -> usize {
        QueueTx::push_slice(self, cmds)
    }
}

impl<const N: usize> CmdSource for QueueRx<'_, N> {
    #[inline(always)]
    fn pop(&mut self) -> Option<StepCmd> {
        QueueRx::pop(self)
    }
}

/// The whole queue as a sink, for an owner of both ends on one thread (the simulator,
/// tests): the same push as the producer's end.
impl<const N: usize> CmdSink for StepQueue<N> {
    fn room(&self) -> usize {
        N - self.queued()
    }
    fn push_slice(&mut self, cmds: &[StepCmd]) -> usize {
        self.split().0.push_slice(cmds)
    }
}

/// The whole queue as a source, likewise: the same pop as the interrupt's end.
impl<const N: usize> CmdSource for StepQueue<N> {
    fn pop(&mut self) -> Option<StepCmd> {
        self.split().1.pop()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interpolation::StepEvent;

    #[test]
    fn fifo_order_wraparound_full_and_clear() {
        let mut q: StepQueue<4> = StepQueue::new();
        let (mut tx, mut rx) = q.split();
        let cmd = |w| StepCmd::new(StepEvent(1), w);
        for round in 0..10u32 {
            for i in 0..4 {
                assert!(tx.push(cmd(round * 10 + i + 2)));
            }
            assert!(tx.is_full());
            assert!(
                !tx.push(cmd(999)),
                "a full ring refuses, it never overwrites"
            );
            assert_eq!(tx.len(), 4);
            for i in 0..4 {
                assert_eq!(rx.pop().map(StepCmd::wait), Some(round * 10 + i + 2));
            }
            assert_eq!(rx.pop(), None);
            assert!(tx.is_empty());
        }
        tx.push(cmd(5));
        tx.push(cmd(6));
        rx.clear();
        assert!(tx.is_empty());
        assert_eq!(rx.pop(), None);
        tx.push(cmd(7));
        assert_eq!(rx.pop().map(StepCmd::wait), Some(7));
    }

    #[test]
    fn direction_bits_of_idle_axes_are_sticky() {
        let mut q: StepQueue<8> = StepQueue::new();
        let (mut tx, mut rx) = q.split();
        for d in [[-1, 1, 0], [0, 1, 0], [0, -1, -1], [1, 0, 0], [0, 0, 0]] {
            tx.push(StepCmd::new(StepEvent::from_deltas(d), 10));
        }
        let dirs: std::vec::Vec<u8> = core::iter::from_fn(|| rx.pop())
            .map(|c| c.tick().dirs())
            .collect();
        // X keeps -X while it does not step, Y and Z keep theirs.
        assert_eq!(dirs, [0b001, 0b001, 0b111, 0b110, 0b110]);
        // The steps (and so the position deltas) are unchanged.
    }
}
