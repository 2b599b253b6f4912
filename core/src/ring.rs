//! Single-producer single-consumer rings between a task and an interrupt: the index
//! ordering they share, and the byte ring that carries the USB serial stream between
//! the USB interrupt and the protocol task. (The step-command ring, whose interrupt
//! side is counted instruction by instruction, is `stepper::queue`; it uses the same
//! ordering helpers.)
//!
//! Why not `heapless::spsc`: its queue views wrap their indices with a run-time `%`
//! (a division and its panic path per byte) and fence with barrier instructions. Here
//! the capacity is a power of two (free-running indices, masked), slots are atomics (no
//! `unsafe`), and on the microcontroller, where producer and consumer run on one CPU
//! (one preempting the other), program order is all the ordering needed: indices are
//! published behind compiler fences with plain loads and stores. On other targets (the
//! simulator and the tests) they use real acquire/release.

use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

/// Producer and consumer run on one CPU core (thread + interrupt).
const SINGLE_CORE: bool = cfg!(all(target_arch = "arm", target_os = "none"));

/// Reads an index the other end publishes; what it published before is visible after.
#[inline(always)]
pub(crate) fn load_acquire(a: &AtomicU32) -> u32 {
    if SINGLE_CORE {
        let v = a.load(Ordering::Relaxed);
        core::sync::atomic::compiler_fence(Ordering::Acquire);
        v
    } else {
        a.load(Ordering::Acquire)
    }
}

/// Publishes an index to the other end, after every slot access before it.
#[inline(always)]
pub(crate) fn store_release(a: &AtomicU32, v: u32) {
    if SINGLE_CORE {
        core::sync::atomic::compiler_fence(Ordering::Release);
        a.store(v, Ordering::Relaxed);
    } else {
        a.store(v, Ordering::Release);
    }
}

/// A byte FIFO of `N` bytes (a power of two, checked at compile time).
pub struct ByteRing<const N: usize> {
    slots: [AtomicU8; N],
    /// Next byte the consumer reads (written by the consumer only).
    head: AtomicU32,
    /// Next byte the producer writes (written by the producer only).
    tail: AtomicU32,
}

impl<const N: usize> Default for ByteRing<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ByteRing<N> {
    const MASK: u32 = {
        assert!(
            N.is_power_of_two() && N <= 1 << 16,
            "ByteRing capacity must be a power of two"
        );
        N as u32 - 1
    };

    pub const fn new() -> Self {
        let _ = Self::MASK;
        ByteRing {
            slots: [const { AtomicU8::new(0) }; N],
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
        }
    }

    /// The two ends. Taking `&mut` once guarantees one producer and one consumer.
    pub fn split(&mut self) -> (ByteTx<'_, N>, ByteRx<'_, N>) {
        (ByteTx { q: self }, ByteRx { q: self })
    }

    /// Bytes waiting (for an owner of both ends, e.g. the simulator).
    pub fn len(&self) -> usize {
        self.tail
            .load(Ordering::Relaxed)
            .wrapping_sub(self.head.load(Ordering::Relaxed)) as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn slot(&self, index: u32) -> Option<&AtomicU8> {
        self.slots.get((index & Self::MASK) as usize)
    }
}

/// The producing end.
pub struct ByteTx<'a, const N: usize> {
    q: &'a ByteRing<N>,
}

impl<const N: usize> ByteTx<'_, N> {
    /// Free bytes (the consumer may free more meanwhile).
    pub fn free(&self) -> usize {
        let used = self
            .q
            .tail
            .load(Ordering::Relaxed)
            .wrapping_sub(load_acquire(&self.q.head));
        N - used as usize
    }

    /// Appends as much of `data` as fits; returns how many bytes it took.
    pub fn push(&mut self, data: &[u8]) -> usize {
        let mut tail = self.q.tail.load(Ordering::Relaxed);
        let n = data.len().min(self.free());
        for &b in data.iter().take(n) {
            if let Some(s) = self.q.slot(tail) {
                s.store(b, Ordering::Relaxed);
            }
            tail = tail.wrapping_add(1);
        }
        store_release(&self.q.tail, tail);
        n
    }
}

/// The consuming end.
pub struct ByteRx<'a, const N: usize> {
    q: &'a ByteRing<N>,
}

impl<const N: usize> ByteRx<'_, N> {
    /// Moves up to `out.len()` bytes out, oldest first; returns how many.
    pub fn pop(&mut self, out: &mut [u8]) -> usize {
        let mut head = self.q.head.load(Ordering::Relaxed);
        let filled = load_acquire(&self.q.tail).wrapping_sub(head) as usize;
        let n = out.len().min(filled);
        for o in out.iter_mut().take(n) {
            *o = self.q.slot(head).map_or(0, |s| s.load(Ordering::Relaxed));
            head = head.wrapping_add(1);
        }
        store_release(&self.q.head, head);
        n
    }

    /// Hands bytes to `take`, oldest first, while it accepts them: a byte it refuses
    /// stays at the head for the next call (the protocol's back-pressure). Returns how
    /// many were taken.
    pub fn pop_while(&mut self, mut take: impl FnMut(u8) -> bool) -> usize {
        let start = self.q.head.load(Ordering::Relaxed);
        let tail = load_acquire(&self.q.tail);
        let mut head = start;
        while head != tail {
            let b = self.q.slot(head).map_or(0, |s| s.load(Ordering::Relaxed));
            if !take(b) {
                break;
            }
            head = head.wrapping_add(1);
        }
        store_release(&self.q.head, head);
        head.wrapping_sub(start) as usize
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        load_acquire(&self.q.tail).wrapping_sub(self.q.head.load(Ordering::Relaxed)) as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;
    use std::vec::Vec;

    #[test]
    fn bytes_come_out_in_order_across_the_wrap_and_a_full_ring_refuses() {
        let mut ring: ByteRing<8> = ByteRing::new();
        let (mut tx, mut rx) = ring.split();
        assert_eq!(tx.free(), 8);
        assert_eq!(tx.push(b"abcdefghij"), 8, "only what fits");
        assert_eq!(tx.free(), 0);
        assert_eq!(
            tx.push(b"x"),
            0,
            "a full ring takes nothing, overwrites nothing"
        );
        let mut out = [0u8; 5];
        assert_eq!(rx.pop(&mut out), 5);
        assert_eq!(&out, b"abcde");
        assert_eq!(tx.push(b"klmno"), 5, "across the end of the buffer");
        let mut all = [0u8; 16];
        assert_eq!(rx.pop(&mut all), 8);
        assert_eq!(&all[..8], b"fghklmno");
        assert_eq!(rx.pop(&mut all), 0);
        assert_eq!(tx.free(), 8);
    }

    #[test]
    fn pop_while_leaves_a_refused_byte_at_the_head() {
        let mut ring: ByteRing<8> = ByteRing::new();
        let (mut tx, mut rx) = ring.split();
        tx.push(b"abcdef");
        assert_eq!(rx.pop_while(|b| b != b'd'), 3);
        assert_eq!(rx.len(), 3);
        assert_eq!(rx.pop_while(|_| false), 0, "d stays");
        tx.push(b"ghij");
        let mut got = std::vec::Vec::new();
        assert_eq!(
            rx.pop_while(|b| {
                got.push(b);
                true
            }),
            7
        );
        assert_eq!(got, b"defghij", "across the end of the buffer");
        assert!(rx.is_empty());
    }

    proptest::proptest! {
        /// Random interleavings of pushes and pops of random sizes behave exactly like
        /// a bounded FIFO: nothing lost, nothing duplicated, nothing reordered.
        #[test]
        fn behaves_like_a_bounded_fifo(
            ops in proptest::collection::vec((proptest::bool::ANY, 0usize..20), 0..400)
        ) {
            let mut ring: ByteRing<16> = ByteRing::new();
            let (mut tx, mut rx) = ring.split();
            let mut model: VecDeque<u8> = VecDeque::new();
            let mut next = 0u8;
            for (is_push, len) in ops {
                if is_push {
                    let data: Vec<u8> = (0..len).map(|i| next.wrapping_add(i as u8)).collect();
                    let took = tx.push(&data);
                    proptest::prop_assert_eq!(took, len.min(16 - model.len()));
                    model.extend(&data[..took]);
                    next = next.wrapping_add(took as u8);
                } else {
                    let mut out = std::vec![0u8; len];
                    let got = rx.pop(&mut out);
                    let want: Vec<u8> = model.drain(..len.min(model.len())).collect();
                    proptest::prop_assert_eq!(&out[..got], &want[..]);
                }
                proptest::prop_assert_eq!(tx.free(), 16 - model.len());
            }
        }
    }
}
