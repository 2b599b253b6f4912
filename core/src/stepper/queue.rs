//! The step-command queue between the segment-preparation task (producer) and the
//! step-timer interrupt (consumer): a single-producer single-consumer ring of packed
//! [`StepCmd`] words.
//!
//! Why not `heapless::spsc`: its dequeue is an out-of-line generic with two `dmb`
//! barriers, a large share of a step interrupt that must stay under 100 instructions.
//! This ring is specialised for the job: a power-of-two capacity (the index mask is
//! one `and`, and the compiler drops the bounds check), free-running `u32` indices, and
//! atomics everywhere (no `unsafe`). Index publication is [`crate::ring`]'s: compiler
//! fences on the single-core microcontroller, acquire/release elsewhere.

use super::{CmdSink, CmdSource, StepCmd};
use crate::ring::{load_acquire, store_release};
use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

/// Step commands the queue holds (4 bytes each): 256 is several milliseconds of
/// stepping at the highest rates, enough to ride out the lower-priority tasks. The
/// firmware and the simulator both use this length.
pub const STEP_QUEUE_LEN: usize = 256;

/// The queue the firmware and the simulator run.
pub type StepCmdQueue = StepQueue<STEP_QUEUE_LEN>;

/// The ring. `N` must be a power of two (checked at compile time).
pub struct StepQueue<const N: usize> {
    slots: [AtomicU32; N],
    /// Next slot the consumer reads (written by the consumer only).
    head: AtomicU32,
    /// Next slot the producer writes (written by the producer only).
    tail: AtomicU32,
    /// Direction bits as of the last command pushed (bit i = axis i negative; written
    /// by the producer only). Kept in the ring, not in the producer's end, so that an
    /// owner of the whole ring (the simulator) may take the ends anew at each use.
    dirs: AtomicU8,
}

impl<const N: usize> Default for StepQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> StepQueue<N> {
    const MASK: u32 = {
        assert!(
            N.is_power_of_two() && N <= 1 << 16,
            "StepQueue capacity must be a power of two"
        );
        N as u32 - 1
    };

    pub const fn new() -> Self {
        let _ = Self::MASK;
        StepQueue {
            slots: [const { AtomicU32::new(0) }; N],
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
            dirs: AtomicU8::new(0),
        }
    }

    /// The two ends. Taking `&mut` guarantees one producer and one consumer.
    pub fn split(&mut self) -> (QueueTx<'_, N>, QueueRx<'_, N>) {
        (QueueTx { q: self }, QueueRx { q: self })
    }

    #[inline(always)]
    fn len(&self) -> u32 {
        self.tail
            .load(Ordering::Relaxed)
            .wrapping_sub(self.head.load(Ordering::Relaxed))
    }
}

/// The producer end (the preparation task).
pub struct QueueTx<'a, const N: usize> {
    q: &'a StepQueue<N>,
}

impl<const N: usize> QueueTx<'_, N> {
    /// Commands waiting (the consumer may take some meanwhile).
    pub fn len(&self) -> usize {
        self.q.len() as usize
    }
    pub fn is_empty(&self) -> bool {
        self.q.len() == 0
    }
    pub fn is_full(&self) -> bool {
        self.q.len() > StepQueue::<N>::MASK
    }
    /// Appends `c`; false (and nothing written) if the ring is full.
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
        let tail = self.q.tail.load(Ordering::Relaxed);
        let used = tail.wrapping_sub(load_acquire(&self.q.head));
        let free = (StepQueue::<N>::MASK + 1).saturating_sub(used) as usize;
        let taken = cmds.get(..free).unwrap_or(cmds);
        let mut dirs = self.q.dirs.load(Ordering::Relaxed);
        let mut at = tail;
        for c in taken {
            let bits = (c.0 >> 24) as u8;
            let mask = bits & 0b111;
            dirs = (dirs & !mask) | ((bits >> 3) & mask);
            let word = (c.0 & !(0b111 << 27)) | (u32::from(dirs) << 27);
            self.q.slots[(at & StepQueue::<N>::MASK) as usize].store(word, Ordering::Relaxed);
            at = at.wrapping_add(1);
        }
        self.q.dirs.store(dirs, Ordering::Relaxed);
        store_release(&self.q.tail, at);
        taken.len()
    }
}

/// The consumer end (the step interrupt).
pub struct QueueRx<'a, const N: usize> {
    q: &'a StepQueue<N>,
}

impl<const N: usize> QueueRx<'_, N> {
    /// Takes the oldest command.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<StepCmd> {
        // A local copy of the reference: the fences below would make the compiler load
        // `self.q` again after each of them.
        let q = self.q;
        let head = q.head.load(Ordering::Relaxed);
        if head == load_acquire(&q.tail) {
            return None;
        }
        let c = q.slots[(head & StepQueue::<N>::MASK) as usize].load(Ordering::Relaxed);
        store_release(&q.head, head.wrapping_add(1));
        Some(StepCmd(c))
    }
    /// Drops everything queued (abort); the producer may keep pushing afterwards.
    pub fn clear(&mut self) {
        store_release(&self.q.head, load_acquire(&self.q.tail));
    }
}

impl<const N: usize> CmdSink for QueueTx<'_, N> {
    fn room(&self) -> usize {
        N - self.len()
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

/// The whole ring as a sink, for an owner of both ends on one thread (the simulator,
/// tests): the same push as the producer's end.
impl<const N: usize> CmdSink for StepQueue<N> {
    fn room(&self) -> usize {
        N - self.len() as usize
    }
    fn push_slice(&mut self, cmds: &[StepCmd]) -> usize {
        self.split().0.push_slice(cmds)
    }
}

/// The whole ring as a source, likewise: the same pop as the interrupt's end.
impl<const N: usize> CmdSource for StepQueue<N> {
    fn pop(&mut self) -> Option<StepCmd> {
        self.split().1.pop()
    }
}

impl<const N: usize> StepQueue<N> {
    /// Commands waiting.
    pub fn queued(&self) -> usize {
        self.len() as usize
    }
    /// Drops everything queued (abort), as the interrupt's end does.
    pub fn clear(&mut self) {
        self.split().1.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interpolation::Tick;

    #[test]
    fn fifo_order_wraparound_full_and_clear() {
        let mut q: StepQueue<4> = StepQueue::new();
        let (mut tx, mut rx) = q.split();
        let cmd = |w| StepCmd::new(Tick(1), w);
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
            tx.push(StepCmd::new(Tick::from_deltas(d), 10));
        }
        let dirs: std::vec::Vec<u8> = core::iter::from_fn(|| rx.pop())
            .map(|c| c.tick().dirs())
            .collect();
        // X keeps -X while it does not step, Y and Z keep theirs.
        assert_eq!(dirs, [0b001, 0b001, 0b111, 0b110, 0b110]);
        // The steps (and so the position deltas) are unchanged.
    }

    #[test]
    fn indices_survive_u32_wrap() {
        let mut q: StepQueue<2> = StepQueue::new();
        q.head.store(u32::MAX - 1, Ordering::Relaxed);
        q.tail.store(u32::MAX - 1, Ordering::Relaxed);
        let (mut tx, mut rx) = q.split();
        for w in 2..20 {
            assert!(tx.push(StepCmd::new(Tick(0), w)));
            assert!(tx.push(StepCmd::new(Tick(0), w + 100)));
            assert_eq!(CmdSink::room(&tx), 0);
            assert_eq!(rx.pop().map(StepCmd::wait), Some(w));
            assert_eq!(rx.pop().map(StepCmd::wait), Some(w + 100));
        }
    }
}
