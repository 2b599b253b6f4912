//! The single-producer single-consumer ring between a task and an interrupt, one
//! mechanism for both of the firmware's queues: the USB serial stream ([`ByteRing`],
//! between the USB interrupt and the protocol task) and the step commands
//! (`stepper::queue`, between segment preparation and the step interrupt, which adds
//! its direction bookkeeping on top). The index arithmetic, the masking and the
//! publication order live here once.
//!
//! Why not `heapless::spsc`: its queue views wrap their indices with a run-time `%` (a
//! division and its panic path per item) and its dequeue is an out-of-line generic
//! with two `dmb` barriers, a large share of a step interrupt that must stay under 100
//! instructions. Here the capacity is a power of two (free-running `u32` indices,
//! masked with one `and`, so the compiler drops the bounds check), slots are atomics
//! (no `unsafe`), and on the microcontroller, where producer and consumer run on one
//! CPU (one preempting the other), program order is all the ordering needed: indices
//! are published behind compiler fences with plain loads and stores. On other targets
//! (the simulator and the tests) they use real acquire/release.

use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

/// Producer and consumer run on one CPU core (thread + interrupt).
const SINGLE_CORE: bool = cfg!(all(target_arch = "arm", target_os = "none"));

/// Reads an index the other end publishes; what it published before is visible after.
#[inline(always)]
fn load_acquire(a: &AtomicU32) -> u32 {
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
fn store_release(a: &AtomicU32, v: u32) {
    if SINGLE_CORE {
        core::sync::atomic::compiler_fence(Ordering::Release);
        a.store(v, Ordering::Relaxed);
    } else {
        a.store(v, Ordering::Release);
    }
}

/// An atomic cell a ring is made of: the ring's own ordering (its indices) makes each
/// slot's value visible to the other end, so slots are read and written relaxed.
pub trait Slot {
    /// What one slot carries.
    type Item: Copy;
    /// A slot's value before anything is written to it.
    const EMPTY: Self;
    fn get(&self) -> Self::Item;
    fn set(&self, v: Self::Item);
}

/// `Slot` for an atomic integer type and the integer it holds.
macro_rules! atomic_slot {
    ($($atomic:ident => $item:ty),*) => {$(
        impl Slot for $atomic {
            type Item = $item;
            const EMPTY: Self = $atomic::new(0);
            #[inline(always)]
            fn get(&self) -> $item {
                self.load(Ordering::Relaxed)
            }
            #[inline(always)]
            fn set(&self, v: $item) {
                self.store(v, Ordering::Relaxed);
            }
        }
    )*};
}

atomic_slot!(AtomicU8 => u8, AtomicU32 => u32);

/// A FIFO of `N` slots (`N` a power of two, checked at compile time).
pub struct Ring<S: Slot, const N: usize> {
    slots: [S; N],
    /// Next slot the consumer reads (written by the consumer only).
    head: AtomicU32,
    /// Next slot the producer writes (written by the producer only).
    tail: AtomicU32,
}

/// The byte ring of the USB serial stream.
pub type ByteRing<const N: usize> = Ring<AtomicU8, N>;
/// The producing end of a [`ByteRing`] (the USB interrupt's receive side, the
/// protocol's replies).
pub type ByteTx<'a, const N: usize> = Tx<'a, AtomicU8, N>;
/// The consuming end of a [`ByteRing`].
pub type ByteRx<'a, const N: usize> = Rx<'a, AtomicU8, N>;

impl<S: Slot, const N: usize> Default for Ring<S, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Slot, const N: usize> Ring<S, N> {
    const MASK: u32 = {
        assert!(
            N.is_power_of_two() && N <= 1 << 16,
            "a ring's capacity must be a power of two"
        );
        N as u32 - 1
    };

    pub const fn new() -> Self {
        let _ = Self::MASK;
        Ring {
            slots: [const { S::EMPTY }; N],
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
        }
    }

    /// The two ends. Taking `&mut` once guarantees one producer and one consumer.
    pub fn split(&mut self) -> (Tx<'_, S, N>, Rx<'_, S, N>) {
        (Tx { ring: self }, Rx { ring: self })
    }

    /// The ends again, for a wrapper that split the ring itself and holds one of each
    /// (so there is still one producer and one consumer): a view of the ring's own
    /// fields, built for free, lets the wrapper's ends be one reference each.
    #[inline(always)]
    pub(crate) fn producer(&self) -> Tx<'_, S, N> {
        Tx { ring: self }
    }
    #[inline(always)]
    pub(crate) fn consumer(&self) -> Rx<'_, S, N> {
        Rx { ring: self }
    }

    /// Items waiting (for an owner of both ends, e.g. the simulator).
    pub fn len(&self) -> usize {
        self.tail
            .load(Ordering::Relaxed)
            .wrapping_sub(self.head.load(Ordering::Relaxed)) as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The slot a free-running index lands on. Never panics: the masked index is below
    /// `N`, which the compiler sees too (no bounds check is emitted).
    #[inline(always)]
    fn slot(&self, index: u32) -> &S {
        &self.slots[(index & Self::MASK) as usize]
    }
}

/// The producing end.
pub struct Tx<'a, S: Slot, const N: usize> {
    ring: &'a Ring<S, N>,
}

impl<S: Slot, const N: usize> Tx<'_, S, N> {
    /// Free slots (the consumer may free more meanwhile).
    #[inline]
    pub fn free(&self) -> usize {
        let used = self
            .ring
            .tail
            .load(Ordering::Relaxed)
            .wrapping_sub(load_acquire(&self.ring.head));
        N - used as usize
    }

    /// Appends as many of `items` as fit, in order, each as `f` makes it, and publishes
    /// them at once; returns how many it took (`f` sees only those).
    #[inline]
    pub fn push_map<T>(&mut self, items: &[T], mut f: impl FnMut(&T) -> S::Item) -> usize {
        let ring = self.ring;
        let taken = items.get(..self.free()).unwrap_or(items);
        let mut tail = ring.tail.load(Ordering::Relaxed);
        for item in taken {
            ring.slot(tail).set(f(item));
            tail = tail.wrapping_add(1);
        }
        store_release(&ring.tail, tail);
        taken.len()
    }

    /// Appends as much of `data` as fits; returns how many items it took.
    pub fn push(&mut self, data: &[S::Item]) -> usize {
        self.push_map(data, |&v| v)
    }

    /// Appends items taken from `next` while it gives them, up to `max` and the room
    /// there is, and publishes them at once; returns how many it took (`next` is not
    /// asked for more than fit). For a producer whose items wait in a queue of its
    /// own (the protocol's replies): they move straight across, with no staging copy.
    pub fn push_from(&mut self, max: usize, mut next: impl FnMut() -> Option<S::Item>) -> usize {
        let ring = self.ring;
        let start = ring.tail.load(Ordering::Relaxed);
        let n = self.free().min(max) as u32;
        let mut tail = start;
        while tail.wrapping_sub(start) < n {
            let Some(v) = next() else {
                break;
            };
            ring.slot(tail).set(v);
            tail = tail.wrapping_add(1);
        }
        store_release(&ring.tail, tail);
        tail.wrapping_sub(start) as usize
    }
}

/// The consuming end.
pub struct Rx<'a, S: Slot, const N: usize> {
    ring: &'a Ring<S, N>,
}

impl<S: Slot, const N: usize> Rx<'_, S, N> {
    /// Takes the oldest item (the step interrupt's path: kept to a few instructions).
    #[inline(always)]
    pub fn pop(&mut self) -> Option<S::Item> {
        // A local copy of the reference: the fences below would make the compiler load
        // `self.ring` again after each of them.
        let ring = self.ring;
        let head = ring.head.load(Ordering::Relaxed);
        if head == load_acquire(&ring.tail) {
            return None;
        }
        let v = ring.slot(head).get();
        store_release(&ring.head, head.wrapping_add(1));
        Some(v)
    }

    /// Moves up to `out.len()` items out, oldest first; returns how many.
    pub fn pop_into(&mut self, out: &mut [S::Item]) -> usize {
        let mut n = 0;
        self.pop_while(|v| match out.get_mut(n) {
            Some(o) => {
                *o = v;
                n += 1;
                true
            }
            None => false,
        })
    }

    /// Copies up to `out.len()` items, oldest first, without taking them: for a
    /// consumer that hands them on in one piece or not at all (the USB endpoint), which
    /// then takes what went out with [`Rx::skip`]. Returns how many.
    pub fn peek_into(&self, out: &mut [S::Item]) -> usize {
        let ring = self.ring;
        let head = ring.head.load(Ordering::Relaxed);
        let n = self.len().min(out.len());
        for (i, o) in out.iter_mut().take(n).enumerate() {
            *o = ring.slot(head.wrapping_add(i as u32)).get();
        }
        n
    }

    /// Drops the oldest `n` items (at most what is queued), e.g. those [`Rx::peek_into`]
    /// copied and the consumer passed on.
    pub fn skip(&mut self, n: usize) {
        let head = self.ring.head.load(Ordering::Relaxed);
        let n = n.min(self.len()) as u32;
        store_release(&self.ring.head, head.wrapping_add(n));
    }

    /// Hands items to `take`, oldest first, while it accepts them: an item it refuses
    /// stays at the head for the next call (the protocol's back-pressure). Returns how
    /// many were taken.
    pub fn pop_while(&mut self, mut take: impl FnMut(S::Item) -> bool) -> usize {
        let ring = self.ring;
        let start = ring.head.load(Ordering::Relaxed);
        let tail = load_acquire(&ring.tail);
        let mut head = start;
        while head != tail && take(ring.slot(head).get()) {
            head = head.wrapping_add(1);
        }
        store_release(&ring.head, head);
        head.wrapping_sub(start) as usize
    }

    /// Drops everything queued (abort); the producer may keep pushing afterwards.
    pub fn clear(&mut self) {
        store_release(&self.ring.head, load_acquire(&self.ring.tail));
    }

    /// Items waiting.
    pub fn len(&self) -> usize {
        load_acquire(&self.ring.tail).wrapping_sub(self.ring.head.load(Ordering::Relaxed)) as usize
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
        assert_eq!(rx.pop_into(&mut out), 5);
        assert_eq!(&out, b"abcde");
        assert_eq!(tx.push(b"klmno"), 5, "across the end of the buffer");
        let mut all = [0u8; 16];
        assert_eq!(rx.pop_into(&mut all), 8);
        assert_eq!(&all[..8], b"fghklmno");
        assert_eq!(rx.pop_into(&mut all), 0);
        assert_eq!(tx.free(), 8);
    }

    #[test]
    fn push_from_takes_only_what_fits_and_asks_for_no_more() {
        let mut ring: ByteRing<8> = ByteRing::new();
        let (mut tx, mut rx) = ring.split();
        let mut source: VecDeque<u8> = b"abcdefghijkl".iter().copied().collect();
        assert_eq!(tx.push_from(3, || source.pop_front()), 3, "at most max");
        assert_eq!(
            tx.push_from(64, || source.pop_front()),
            5,
            "at most the room"
        );
        assert_eq!(source.len(), 4, "nothing taken that did not fit");
        let mut out = [0u8; 6];
        assert_eq!(rx.pop_into(&mut out), 6);
        assert_eq!(&out, b"abcdef");
        assert_eq!(
            tx.push_from(64, || source.pop_front()),
            4,
            "until the source is dry"
        );
        let mut all = [0u8; 8];
        assert_eq!(rx.pop_into(&mut all), 6);
        assert_eq!(&all[..6], b"ghijkl");
    }

    #[test]
    fn peek_leaves_the_items_until_skipped() {
        let mut ring: ByteRing<8> = ByteRing::new();
        let (mut tx, mut rx) = ring.split();
        tx.push(b"abcdef");
        rx.skip(4);
        tx.push(b"ghijkl");
        let mut out = [0u8; 5];
        assert_eq!(rx.peek_into(&mut out), 5);
        assert_eq!(&out, b"efghi", "across the end of the buffer");
        assert_eq!(rx.len(), 8, "nothing taken");
        rx.skip(3);
        let mut all = [0u8; 16];
        assert_eq!(rx.peek_into(&mut all), 5);
        assert_eq!(&all[..5], b"hijkl");
        rx.skip(99);
        assert!(rx.is_empty(), "at most what is queued");
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

    #[test]
    fn indices_survive_u32_wrap() {
        let mut ring: Ring<AtomicU32, 2> = Ring::new();
        ring.head.store(u32::MAX - 1, Ordering::Relaxed);
        ring.tail.store(u32::MAX - 1, Ordering::Relaxed);
        let (mut tx, mut rx) = ring.split();
        for w in 2..20 {
            assert_eq!(tx.push(&[w, w + 100, w + 200]), 2, "two fit");
            assert_eq!(tx.free(), 0);
            assert_eq!(rx.len(), 2);
            assert_eq!(rx.pop(), Some(w));
            assert_eq!(rx.pop(), Some(w + 100));
            assert_eq!(rx.pop(), None);
        }
    }

    #[test]
    fn push_map_sees_only_what_it_stores_and_clear_empties() {
        let mut ring: Ring<AtomicU32, 4> = Ring::new();
        let (mut tx, mut rx) = ring.split();
        let mut seen = 0;
        let took = tx.push_map(&[1u8; 10], |&v| {
            seen += 1;
            u32::from(v)
        });
        assert_eq!((took, seen), (4, 4));
        rx.clear();
        assert!(rx.is_empty());
        assert_eq!(rx.pop(), None);
        assert_eq!(tx.push(&[7]), 1, "the producer goes on after a clear");
        assert_eq!(rx.pop(), Some(7));
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
                    let got = rx.pop_into(&mut out);
                    let want: Vec<u8> = model.drain(..len.min(model.len())).collect();
                    proptest::prop_assert_eq!(&out[..got], &want[..]);
                }
                proptest::prop_assert_eq!(tx.free(), 16 - model.len());
            }
        }
    }
}
