//! The step-timer interrupt's work: pop a command, pulse its steps, set the direction
//! pins for the next one and report the timer reload. Integer only, no loops, no
//! division; a wait longer than the 16-bit timer is split into several reloads.
//!
//! Direction bits for a step are output one full period before its pulse (when its
//! command is fetched), which gives every driver its direction set-up time for free.
//! The emergency stop latches [`Executor::halt`]: from then on no step is emitted until
//! [`Executor::reset`], whatever is still queued.

use super::{CmdSource, StepCmd};
use crate::motion::StepPos;

/// What the interrupt must do now.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IsrOut {
    /// Step pins to pulse now (bit i = axis i).
    pub step: u8,
    /// Direction pins to hold from now (bit i set = axis i negative).
    pub dir: u8,
    /// Timer ticks until the next interrupt; 0 = stop the timer (queue empty or halted).
    pub reload: u32,
}

/// Per-axis position change of each 6-bit tick (steps in bits 0-2, negative directions
/// in bits 3-5): three loads and adds instead of three branches in the interrupt.
static STEP_DELTA: [[i8; 3]; 64] = {
    let mut t = [[0i8; 3]; 64];
    let mut bits = 0;
    while bits < 64 {
        let mut axis = 0;
        while axis < 3 {
            if bits >> axis & 1 != 0 {
                t[bits][axis] = if bits >> (axis + 3) & 1 != 0 { -1 } else { 1 };
            }
            axis += 1;
        }
        bits += 1;
    }
    t
};

/// Interrupt-side state.
#[derive(Clone, Debug)]
pub struct Executor {
    pos: StepPos,
    /// Tick bits of the command whose wait is running.
    pending: u8,
    /// Wait still to run after the present reload.
    remaining: u32,
    running: bool,
    halted: bool,
    max_reload: u32,
}

impl Executor {
    /// `max_reload` is the timer's largest period (0xFFFF for a 16-bit timer).
    pub const fn new(position: StepPos, max_reload: u32) -> Self {
        Executor {
            pos: position,
            pending: 0,
            remaining: 0,
            running: false,
            halted: false,
            max_reload: if max_reload == 0 { 1 } else { max_reload },
        }
    }

    /// Machine position in steps (every pulse emitted so far).
    pub fn position(&self) -> StepPos {
        self.pos
    }
    pub fn is_running(&self) -> bool {
        self.running
    }
    pub fn is_halted(&self) -> bool {
        self.halted
    }

    /// Starts the timer if it is idle and a command is ready: returns the outputs for
    /// the start (direction pins, first reload). `None` if nothing to do.
    pub fn start(&mut self, q: &mut impl CmdSource) -> Option<IsrOut> {
        if self.running || self.halted {
            return None;
        }
        let c = q.pop()?;
        self.running = true;
        Some(self.load(c, 0))
    }

    #[inline(always)]
    fn load(&mut self, c: StepCmd, step: u8) -> IsrOut {
        let bits = c.tick().0;
        self.pending = bits;
        // The pins follow the next command's direction bits. An axis that does not step
        // in it may flip meanwhile: drivers read the pin only at a step edge, and every
        // later step's direction is again set a whole period ahead of it.
        let wait = c.wait();
        let reload = if wait > self.max_reload {
            self.max_reload
        } else {
            wait
        };
        self.remaining = wait - reload;
        IsrOut {
            step,
            dir: bits >> 3,
            reload,
        }
    }

    /// The step-timer interrupt.
    #[inline(always)]
    pub fn on_interrupt(&mut self, q: &mut impl CmdSource) -> IsrOut {
        // A halt clears `running`, so one test covers both.
        if !self.running {
            return IsrOut {
                step: 0,
                dir: self.pending >> 3,
                reload: 0,
            };
        }
        if self.remaining > 0 {
            let reload = if self.remaining > self.max_reload {
                self.max_reload
            } else {
                self.remaining
            };
            self.remaining -= reload;
            return IsrOut {
                step: 0,
                dir: self.pending >> 3,
                reload,
            };
        }
        // The pending command's wait is over: its steps happen now.
        let bits = self.pending;
        let delta = &STEP_DELTA[usize::from(bits & 0x3f)];
        self.pos[0] = self.pos[0].wrapping_add(i32::from(delta[0]));
        self.pos[1] = self.pos[1].wrapping_add(i32::from(delta[1]));
        self.pos[2] = self.pos[2].wrapping_add(i32::from(delta[2]));
        let step = bits & 0b111;
        match q.pop() {
            Some(c) => self.load(c, step),
            None => {
                self.running = false;
                self.pending = 0;
                IsrOut {
                    step,
                    dir: bits >> 3,
                    reload: 0,
                }
            }
        }
    }

    /// Emergency stop: no further step until [`Executor::reset`].
    pub fn halt(&mut self) {
        self.halted = true;
        self.running = false;
        self.remaining = 0;
        self.pending = 0;
    }

    /// Clears a halt (after the queue was flushed), keeping the position.
    pub fn reset(&mut self) {
        self.halted = false;
        self.running = false;
        self.remaining = 0;
        self.pending = 0;
    }

    /// Sets the machine position (G92-like re-zero or homing), only while idle.
    pub fn set_position(&mut self, p: StepPos) -> bool {
        if self.running {
            return false;
        }
        self.pos = p;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interp::Tick;
    use heapless::spsc::Queue;

    #[test]
    fn emits_steps_at_the_commanded_times_and_splits_long_waits() {
        let mut q: Queue<StepCmd, 8> = Queue::new();
        q.enqueue(StepCmd::new(Tick::from_deltas([1, 0, 0]), 100))
            .unwrap();
        q.enqueue(StepCmd::new(Tick::from_deltas([0, -1, 0]), 150_000))
            .unwrap();
        q.enqueue(StepCmd::new(Tick::from_deltas([1, 1, 0]), 10))
            .unwrap();
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
        let mut q: Queue<StepCmd, 8> = Queue::new();
        q.enqueue(StepCmd::new(Tick::from_deltas([1, 0, 0]), 50))
            .unwrap();
        q.enqueue(StepCmd::new(Tick::from_deltas([-1, 0, 0]), 50))
            .unwrap();
        let mut e = Executor::new([0; 3], 0xFFFF);
        assert_eq!(e.start(&mut q).unwrap().dir & 1, 0);
        // The +X step is emitted while the pins already show -X for the next one.
        let o = e.on_interrupt(&mut q);
        assert_eq!((o.step, o.dir & 1), (1, 1));
    }

    #[test]
    fn halt_stops_every_further_step() {
        let mut q: Queue<StepCmd, 8> = Queue::new();
        for _ in 0..5 {
            q.enqueue(StepCmd::new(Tick::from_deltas([1, 0, 0]), 10))
                .unwrap();
        }
        let mut e = Executor::new([0; 3], 0xFFFF);
        e.start(&mut q).unwrap();
        assert_eq!(e.on_interrupt(&mut q).step, 1);
        e.halt();
        for _ in 0..10 {
            let o = e.on_interrupt(&mut q);
            assert_eq!((o.step, o.reload), (0, 0));
        }
        assert!(e.start(&mut q).is_none());
        assert_eq!(e.position(), [1, 0, 0]);
    }
}
