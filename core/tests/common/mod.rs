//! A fake planner for host tests: a bounded queue executed by `step()`, which moves
//! every axis of the head move toward its target by at most `rate` steps per call,
//! so switches can be hit part-way and holds stop between steps.
#![allow(dead_code)]

pub mod flash;

use inkstep_core::machine::{MotionControl, MotionState, QueueFull};
use inkstep_core::motion::Command;
use inkstep_core::motion::StepPos;
use inkstep_core::protocol::Protocol;
use std::collections::VecDeque;

/// The protocol driven as the controller's service drives it (bytes in one by one
/// until one is refused, responses out one by one, lines one at a time), for the
/// tests of the protocol alone.
pub trait Drive {
    /// Offer `bytes`; returns how many were taken (the rest come again later).
    fn receive<M: MotionControl>(&mut self, bytes: &[u8], m: &mut M, now_ms: u32) -> usize;
    /// Up to `buf.len()` bytes of responses.
    fn read_output(&mut self, buf: &mut [u8]) -> usize;
    /// Every line that can run now.
    fn poll<M: MotionControl>(&mut self, m: &mut M, now_ms: u32);
}

impl Drive for Protocol {
    fn receive<M: MotionControl>(&mut self, bytes: &[u8], m: &mut M, now_ms: u32) -> usize {
        bytes
            .iter()
            .take_while(|&&b| self.take_byte(b, m, now_ms))
            .count()
    }

    fn read_output(&mut self, buf: &mut [u8]) -> usize {
        let mut n = 0;
        for slot in buf.iter_mut() {
            let Some(b) = self.pop_output() else { break };
            *slot = b;
            n += 1;
        }
        n
    }

    fn poll<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) {
        while self.poll_one(m, now_ms) {}
    }
}

pub struct FakePlanner {
    pub queue: VecDeque<Command>,
    pub cap: usize,
    pub pos: StepPos,
    pub holding: bool,
    /// A hold was requested while moving: one more step() to come to rest.
    pub stopping: bool,
    pub rate: i32,
    pub overrides: (u8, u8),
    pub clears: u32,
    /// Every command accepted, in order.
    pub log: Vec<Command>,
}

impl FakePlanner {
    pub fn new(cap: usize) -> Self {
        FakePlanner {
            queue: VecDeque::new(),
            cap,
            pos: [0; 3],
            holding: false,
            stopping: false,
            rate: 1_000_000,
            overrides: (100, 100),
            clears: 0,
            log: Vec::new(),
        }
    }

    /// Advance the head command.
    pub fn step(&mut self) {
        if self.holding {
            if !self.stopping {
                return;
            }
            self.stopping = false;
        }
        let Some(head) = self.queue.front() else {
            return;
        };
        let done = match head {
            Command::Move(mv) => {
                for (p, t) in self.pos.iter_mut().zip(mv.target.iter()) {
                    let d = (i64::from(*t) - i64::from(*p))
                        .clamp(-i64::from(self.rate), i64::from(self.rate));
                    *p = (i64::from(*p) + d) as i32;
                }
                self.pos == mv.target
            }
            _ => true,
        };
        if done {
            self.queue.pop_front();
        }
    }

    /// A dwell runs with nothing behind it.
    fn dwell_alone(&self) -> bool {
        self.queue.len() == 1 && matches!(self.queue.front(), Some(Command::Dwell { .. }))
    }

    pub fn run_all(&mut self) {
        for _ in 0..1_000_000 {
            if self.queue.is_empty() || self.holding {
                return;
            }
            self.step();
        }
    }
}

impl MotionControl for FakePlanner {
    fn push(&mut self, cmd: Command) -> Result<(), QueueFull> {
        if self.queue.len() >= self.cap {
            return Err(QueueFull);
        }
        self.queue.push_back(cmd);
        self.log.push(cmd);
        Ok(())
    }
    fn queued(&self) -> usize {
        self.queue.len()
    }
    fn capacity(&self) -> usize {
        self.cap
    }
    fn hold(&mut self) {
        if !self.holding {
            self.stopping = !self.queue.is_empty();
        }
        self.holding = true;
    }
    fn resume(&mut self) {
        self.holding = false;
        self.stopping = false;
    }
    fn motion(&self) -> MotionState {
        let moving = !self.queue.is_empty() && (!self.holding || self.stopping);
        match (self.holding, moving) {
            (true, true) => MotionState::Holding,
            (true, false) => MotionState::Held,
            (false, true) if self.dwell_alone() => MotionState::Dwelling,
            (false, true) => MotionState::Running,
            (false, false) => MotionState::Idle,
        }
    }
    fn clear(&mut self) {
        self.queue.clear();
        self.holding = false;
        self.stopping = false;
        self.clears += 1;
    }
    fn set_overrides(&mut self, feed: u8, rapid: u8) {
        self.overrides = (feed, rapid);
    }
    fn position(&self) -> StepPos {
        self.pos
    }
    fn set_position(&mut self, pos: StepPos) {
        self.pos = pos;
    }
    fn speed(&self) -> f32 {
        if self.is_moving() && !self.dwell_alone() {
            600.0
        } else {
            0.0
        }
    }
}

/// Read all pending output as text.
pub fn drain(p: &mut Protocol) -> String {
    let mut buf = [0u8; 256];
    let mut s = String::new();
    loop {
        let n = p.read_output(&mut buf);
        if n == 0 {
            return s;
        }
        s.push_str(&String::from_utf8_lossy(&buf[..n]));
    }
}

/// Send text, poll until everything is consumed and answered, return the output.
pub fn send(p: &mut Protocol, m: &mut FakePlanner, text: &str) -> String {
    let mut rest = text.as_bytes();
    let mut out = String::new();
    for _ in 0..100_000 {
        let n = p.receive(rest, m, 0);
        rest = &rest[n..];
        p.poll(m, 0);
        out.push_str(&drain(p));
        if rest.is_empty() {
            break;
        }
        m.step();
    }
    // Then read until the protocol is done talking: a listing continues poll by poll
    // as the output buffer empties, like the firmware's task every millisecond.
    loop {
        p.poll(m, 0);
        let more = drain(p);
        if more.is_empty() {
            return out;
        }
        out.push_str(&more);
    }
}
