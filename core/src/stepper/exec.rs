//! The step-timer interrupt's work: pop a command, count its steps, set the direction
//! pins for the next one and report the timer reload. Integer only, no loops, no
//! division; a wait longer than the 16-bit timer is split into several reloads.
//!
//! Direction bits for a step are output one full period before its pulse (when its
//! command is fetched), which gives every driver its direction set-up time for free;
//! a reversal of an axis whose pulse is still high first runs a short turn guard
//! period ([`Executor::set_turn_guard`]). Every reload is at least 2 ticks, so a board
//! can program a timer with `reload - 1` without a check. [`Executor::halt`] stops the
//! command in flight; that nothing starts again until the queue was flushed and the
//! halt released is the shell's [`HaltLatch`](crate::halt::HaltLatch), which it looks
//! at before [`Executor::start`].
//!
//! Shaped for the interrupt's instruction count: idle and "more of a long wait" share
//! one test of `remaining` (idle is a sentinel value), the position changes come from
//! a table, and each result carries the steps a hardware-pulsing board arms next.

use super::{CmdSource, StepCmd};
use crate::motion::StepPos;

/// What the interrupt must do now.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IsrOut {
    /// Step pins to pulse now (bit i = axis i).
    pub step: u8,
    /// The whole tick of the steps emitted now: `step` plus their own directions
    /// (what a 4-phase output advances its coils by).
    pub tick: u8,
    /// Direction pins to hold from now (bit i set = axis i negative).
    pub dir: u8,
    /// Direction pins that differ from the previous result's `dir` (0 = none).
    pub dir_changed: u8,
    /// Steps due when the period programmed now (`reload`) ends; a board that pulses
    /// in hardware arms its outputs with these, one period ahead.
    pub arm: u8,
    /// Timer counts until the next interrupt (>= 2); 0 = stop the timer (queue empty or
    /// halted).
    pub reload: u32,
}

/// Position change of a 6-bit tick (steps in bits 0-2, negative directions in bits
/// 3-5) along one axis.
const fn step_delta(bits: usize, axis: usize) -> i8 {
    if bits >> axis & 1 == 0 {
        0
    } else if bits >> (axis + 3) & 1 != 0 {
        -1
    } else {
        1
    }
}

/// X and Y change of each tick, packed as one 64-bit value `dx + dy * 2^32` (see
/// [`Executor`]'s `xy`); Z's in [`STEP_DZ`]. Two loads and three adds instead of three
/// branches in the interrupt.
static STEP_DXY: [i64; 64] = {
    let mut t = [0i64; 64];
    let mut bits = 0;
    while bits < 64 {
        t[bits] = step_delta(bits, 0) as i64 + ((step_delta(bits, 1) as i64) << 32);
        bits += 1;
    }
    t
};

/// Z change of each tick.
static STEP_DZ: [i8; 64] = {
    let mut t = [0i8; 64];
    let mut bits = 0;
    while bits < 64 {
        t[bits] = step_delta(bits, 2);
        bits += 1;
    }
    t
};

/// X and Y in one linear 64-bit code, `x + y * 2^32`: adding a packed delta moves both
/// at once, and the code of any pair of i32 positions decodes exactly.
const fn pack_xy(x: i32, y: i32) -> i64 {
    (x as i64).wrapping_add((y as i64) << 32)
}

const fn unpack_xy(xy: i64) -> (i32, i32) {
    let x = xy as i32;
    (x, (xy.wrapping_sub(x as i64) >> 32) as i32)
}

/// `remaining` while idle: no command is running (larger than any wait).
const IDLE: u32 = u32::MAX;

/// Interrupt-side state.
#[derive(Clone, Debug)]
pub struct Executor {
    /// X and Y position, packed by [`pack_xy`].
    xy: i64,
    z: i32,
    /// Step event bits of the command whose wait is running.
    pending: u8,
    /// Wait still to run after the present reload; [`IDLE`] when not running.
    remaining: u32,
    /// Direction pins as last output.
    dir: u8,
    /// Direction pins to output when the turn guard period ends.
    turn_dir: u8,
    /// A turn guard period is running.
    turning: bool,
    /// Length of the turn guard period in ticks (0 = off), see [`Executor::set_turn_guard`].
    turn_guard: u32,
    max_reload: u32,
}

impl Executor {
    /// `max_reload` is the timer's largest period (0xFFFF for a 16-bit timer, 0x10000
    /// if the board writes `reload - 1`); at least 4.
    pub const fn new(position: StepPos, max_reload: u32) -> Self {
        Executor {
            xy: pack_xy(position[0], position[1]),
            z: position[2],
            pending: 0,
            remaining: IDLE,
            dir: 0,
            turn_dir: 0,
            turning: false,
            turn_guard: 0,
            max_reload: if max_reload < 4 { 4 } else { max_reload },
        }
    }

    /// Machine position in steps (every pulse emitted so far).
    pub fn position(&self) -> StepPos {
        let (x, y) = unpack_xy(self.xy);
        [x, y, self.z]
    }
    pub fn is_running(&self) -> bool {
        self.remaining != IDLE
    }

    /// Direction pins must not change while a step pulse of their axis is high. With a
    /// guard of `ticks` (the pulse width plus the drivers' hold time), a command that
    /// reverses an axis whose pulse starts at the same moment begins with a guard
    /// period of that length, at whose end the pins turn; the rest of the command's
    /// wait follows (at least 2 ticks, so a reversal faster than the guard is late by
    /// the difference rather than wrong). 0 turns the guard off (pins turn at once).
    pub fn set_turn_guard(&mut self, ticks: u32) {
        self.turn_guard = if ticks == 0 {
            0
        } else {
            // max/min, not clamp: clamp's min <= max assertion would give the step
            // interrupt a panic path (and its stack), though max_reload >= 4 here.
            ticks.max(2).min(self.max_reload)
        };
    }

    /// Starts the timer if it is idle and a command is ready: returns the outputs for
    /// the start (direction pins, first reload). `None` if nothing to do.
    pub fn start(&mut self, q: &mut impl CmdSource) -> Option<IsrOut> {
        if self.is_running() {
            return None;
        }
        let c = q.pop()?;
        Some(self.load(c, 0, 0))
    }

    /// The next reload out of a wait of `w` ticks and what is left after it. Up to
    /// `max_reload` in one period; longer waits go in parts of at most `max_reload -
    /// 1` that always leave at least half of `max_reload`: never a 1-tick reload, and
    /// never a last part shorter than the interrupt that starts it (a board whose
    /// timer waits for the interrupt at each period's end would come late there).
    #[inline(always)]
    fn part(&self, w: u32) -> (u32, u32) {
        if w > self.max_reload {
            self.split(w)
        } else {
            (w, 0)
        }
    }

    /// [`Executor::part`] of a wait longer than one period: marked cold, so that the
    /// interrupt's path for the usual wait stays one compare and a branch.
    #[cold]
    fn split(&self, w: u32) -> (u32, u32) {
        let reload = (self.max_reload - 1).min(w - self.max_reload / 2);
        (reload, w - reload)
    }

    #[inline(always)]
    fn load(&mut self, c: StepCmd, step: u8, tick: u8) -> IsrOut {
        let bits = c.tick().0;
        self.pending = bits;
        let mask = bits & 0b111;
        // The pins follow the command's direction bits. The firmware's queue makes them
        // sticky (an axis that does not step keeps its last direction, see
        // `queue::QueueTx::push`), so a pin only changes where a step needs it.
        let dir = bits >> 3;
        // StepCmd::new keeps every wait >= 2.
        let wait = c.wait();
        let dir_changed = dir ^ self.dir;
        if dir_changed & step != 0 && self.turn_guard != 0 {
            self.turn_dir = dir;
            self.turning = true;
            self.remaining = wait.saturating_sub(self.turn_guard).max(2);
            return IsrOut {
                step,
                tick,
                dir: self.dir,
                dir_changed: 0,
                arm: 0,
                reload: self.turn_guard,
            };
        }
        self.dir = dir;
        let (reload, rest) = self.part(wait);
        self.remaining = rest;
        IsrOut {
            step,
            tick,
            dir,
            dir_changed,
            arm: if rest == 0 { mask } else { 0 },
            reload,
        }
    }

    /// The step-timer interrupt.
    #[inline(always)]
    pub fn on_interrupt(&mut self, q: &mut impl CmdSource) -> IsrOut {
        if self.remaining != 0 {
            return self.continue_or_idle();
        }
        // The pending command's wait is over: its steps happen now.
        let bits = self.pending;
        let i = usize::from(bits & 0x3f);
        self.xy = self.xy.wrapping_add(STEP_DXY[i]);
        self.z = self.z.wrapping_add(i32::from(STEP_DZ[i]));
        let step = bits & 0b111;
        match q.pop() {
            Some(c) => self.load(c, step, bits),
            None => {
                self.remaining = IDLE;
                self.pending = 0;
                IsrOut {
                    step,
                    tick: bits,
                    dir: self.dir,
                    dir_changed: 0,
                    arm: 0,
                    reload: 0,
                }
            }
        }
    }

    /// Idle (or halted): nothing to do; or the next part of a long wait or of a turn
    /// guard's command.
    #[inline(always)]
    fn continue_or_idle(&mut self) -> IsrOut {
        let mut out = IsrOut {
            step: 0,
            tick: 0,
            dir: self.dir,
            dir_changed: 0,
            arm: 0,
            reload: 0,
        };
        if self.remaining == IDLE {
            return out;
        }
        if self.turning {
            // The guard period is over: the pulse has ended, the pins may turn.
            self.turning = false;
            out.dir_changed = self.turn_dir ^ self.dir;
            self.dir = self.turn_dir;
            out.dir = self.dir;
        }
        let (reload, rest) = self.part(self.remaining);
        self.remaining = rest;
        out.reload = reload;
        if rest == 0 {
            out.arm = self.pending & 0b111;
        }
        out
    }

    /// Steps due when the period just programmed (the last `reload`) ends: the pending
    /// command's steps if this is its last (or only) part of the wait, else none.
    #[inline(always)]
    pub fn steps_at_period_end(&self) -> u8 {
        if self.remaining == 0 {
            self.pending & 0b111
        } else {
            0
        }
    }

    /// Emergency stop: the command in flight ends here, and no step comes until the
    /// next [`Executor::start`] (which the shell's halt latch holds back).
    pub fn halt(&mut self) {
        self.idle();
    }

    fn idle(&mut self) {
        self.remaining = IDLE;
        self.pending = 0;
        self.turning = false;
    }

    /// Sets the machine position (G92-like re-zero or homing), only while idle.
    pub fn set_position(&mut self, p: StepPos) -> bool {
        if self.is_running() {
            return false;
        }
        self.xy = pack_xy(p[0], p[1]);
        self.z = p[2];
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interpolation::StepEvent;
    use crate::stepper::queue::StepQueue;
    use crate::stepper::CmdSink;

    /// A queue holding one command per `(axis deltas, wait)` pair, in order.
    fn queue_of(cmds: &[([i8; 3], u32)]) -> StepQueue<8> {
        let mut q = StepQueue::new();
        for &(d, w) in cmds {
            assert_eq!(
                q.push_slice(&[StepCmd::new(StepEvent::from_deltas(d), w)]),
                1
            );
        }
        q
    }

    #[test]
    fn emits_steps_at_the_commanded_times_and_splits_long_waits() {
        let mut q = queue_of(&[([1, 0, 0], 100), ([0, -1, 0], 150_000), ([1, 1, 0], 10)]);
        let mut e = Executor::new([0; 3], 0xFFFF);
        let first = e.start(&mut q).unwrap();
        assert_eq!(first.reload, 100);
        let mut t = u64::from(first.reload);
        let mut events = std::vec::Vec::new();
        loop {
            let o = e.on_interrupt(&mut q);
            if o.step != 0 {
                events.push((t, o.step, e.position()));
            }
            if o.reload == 0 {
                break;
            }
            t += u64::from(o.reload);
        }
        assert_eq!(
            events,
            std::vec![
                (100, 1, [1, 0, 0]),
                (150_100, 2, [1, -1, 0]),
                (150_110, 3, [2, 0, 0])
            ]
        );
        assert!(!e.is_running());
    }

    #[test]
    fn direction_is_set_one_period_before_its_step() {
        let mut q = queue_of(&[([1, 0, 0], 50), ([-1, 0, 0], 50)]);
        let mut e = Executor::new([0; 3], 0xFFFF);
        assert_eq!(e.start(&mut q).unwrap().dir & 1, 0);
        // The +X step is emitted while the pins already show -X for the next one.
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.dir & 1), (1, 1));
    }

    #[test]
    fn a_reversal_turns_the_pin_only_after_the_guard_and_keeps_the_timing() {
        let mut q = queue_of(&[
            ([1, 1, 0], 1000),
            ([1, 1, 0], 1000),
            ([-1, 1, 0], 1000),
            ([-1, 1, 0], 100),
        ]);
        let mut e = Executor::new([0; 3], 0xFFFF);
        e.set_turn_guard(300);
        assert_eq!(e.start(&mut q).unwrap().reload, 1000);
        // +X step; the next command also goes +X: no guard.
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.dir & 1, o.reload), (3, 0, 1000));
        assert_eq!(e.steps_at_period_end(), 3);
        // +X step while the next command reverses X: the pin holds for the guard.
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.tick, o.dir & 1, o.reload), (3, 3, 0, 300));
        assert_eq!(e.steps_at_period_end(), 0, "no pulse at the guard's end");
        let o = e.on_interrupt(&mut q);
        assert_eq!(
            (o.step, o.dir & 1, o.reload),
            (0, 1, 700),
            "the pin turns, the wait completes"
        );
        assert_eq!(e.steps_at_period_end(), 3);
        // -X step, next also -X: no guard.
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.tick, o.reload), (3, 3 | 8, 100));
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.reload), (3, 0));
        assert_eq!(e.position(), [0, 4, 0]);
    }

    #[test]
    fn a_reversal_faster_than_the_guard_is_late_not_lost() {
        let mut q = queue_of(&[([1, 0, 0], 50), ([-1, 0, 0], 50)]);
        let mut e = Executor::new([0; 3], 0xFFFF);
        e.set_turn_guard(300);
        e.start(&mut q).unwrap();
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.dir & 1, o.reload), (1, 0, 300));
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.dir & 1, o.reload), (0, 1, 2));
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.reload), (1, 0));
        assert_eq!(e.position(), [0, 0, 0]);
    }

    #[test]
    fn long_waits_split_into_reloads_of_at_least_two_and_arm_only_the_last() {
        for wait in [65_535, 65_536, 65_537, 65_538, 131_073, 200_000] {
            let mut q = queue_of(&[([1, 0, 0], wait)]);
            let mut e = Executor::new([0; 3], 0x1_0000);
            let first = e.start(&mut q).unwrap();
            let (mut total, mut parts) = (first.reload, std::vec![first]);
            loop {
                let o = e.on_interrupt(&mut q);
                if o.step != 0 {
                    break;
                }
                total += o.reload;
                parts.push(o);
            }
            assert_eq!(total, wait);
            assert!(
                parts.iter().all(|p| (2..=0x1_0000).contains(&p.reload)),
                "{wait}: {parts:?}"
            );
            if wait > 0x1_0000 {
                assert!(
                    parts.iter().all(|p| p.reload >= 0x8000),
                    "{wait}: no part shorter than half the timer's range: {parts:?}"
                );
            }
            let armed: std::vec::Vec<u8> = parts.iter().map(|p| p.arm).collect();
            assert_eq!(
                armed.last(),
                Some(&1),
                "{wait}: the last part arms the step"
            );
            assert!(
                armed[..armed.len() - 1].iter().all(|&a| a == 0),
                "{wait}: {armed:?}"
            );
        }
    }

    #[test]
    fn packed_xy_decodes_every_position_and_moves_linearly() {
        let edge = [
            i32::MIN,
            i32::MIN + 1,
            -70_000,
            -1,
            0,
            1,
            65_536,
            i32::MAX - 1,
            i32::MAX,
        ];
        for &x in &edge {
            for &y in &edge {
                assert_eq!(unpack_xy(pack_xy(x, y)), (x, y));
                for (dx, dy) in [
                    (1, 0),
                    (-1, 0),
                    (0, 1),
                    (0, -1),
                    (1, 1),
                    (-1, -1),
                    (1, -1),
                    (-1, 1),
                ] {
                    let (Some(x2), Some(y2)) = (x.checked_add(dx), y.checked_add(dy)) else {
                        continue; // positions never come near the i32 range's ends
                    };
                    let moved = pack_xy(x, y).wrapping_add(pack_xy(dx, dy));
                    assert_eq!(unpack_xy(moved), (x2, y2));
                }
            }
        }
        for bits in 0..64u8 {
            let i = usize::from(bits);
            let d = StepEvent(bits).deltas();
            assert_eq!(unpack_xy(STEP_DXY[i]), (i32::from(d[0]), i32::from(d[1])));
            assert_eq!(STEP_DZ[i], d[2]);
        }
    }

    #[test]
    fn halt_stops_every_further_step() {
        let mut q = queue_of(&[([1, 0, 0], 10); 5]);
        let mut e = Executor::new([0; 3], 0xFFFF);
        e.start(&mut q).unwrap();
        assert_eq!(e.on_interrupt(&mut q).step, 1);
        e.halt();
        for _ in 0..10 {
            let o = e.on_interrupt(&mut q);
            assert_eq!((o.step, o.reload), (0, 0));
        }
        assert_eq!(e.position(), [1, 0, 0]);
    }
}
