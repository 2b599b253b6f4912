//! Segment preparation: pulls ticks from the interpolator of the block in execution
//! and gives each one its time from the block's velocity profile, producing
//! [`StepCmd`]s for the interrupt. Runs in a task below the step timer; floating
//! point is fine here, per segment, never per step and never in [`super::exec`].
//!
//! Timing. A tick's path position is where the ideal path is when the tick happens: on
//! a line, k times the line's length over its tick count; on a DDA circle, the point of
//! the circle at the tick's major coordinate; along other curves, the sum of the ticks'
//! lengths (see [`crate::interpolation::Next`]). Its ideal time is when the profile reaches
//! that position. Preparation cuts a run of ticks into segments; for each it evaluates
//! the ideal time and its slope (speed, and the path's rate per tick) exactly at both
//! ends (f32, phase-local so that rounding stays far below a microsecond), and times the
//! ticks in between by the cubic Hermite polynomial through them, evaluated by forward
//! differences: per tick three 64-bit additions (`Segment`). A segment is as long as
//! the polynomial's error bound allows: `max_error_s` (0.5 µs) over h^4/384 times the
//! largest fourth derivative of the tick time, which follows from the profile's
//! acceleration and jerk, the speed and the path's curvature (at most 256 ticks, never
//! across a phase of the profile). Cruising along a line the time is linear, so one
//! segment takes up to 2048 ticks; ramps of constant acceleration are timed exactly
//! in integers (`RampTiming`), other ramps take shorter segments, and the first tick of a
//! phase (or from rest) its own. Every segment starts on the exact time of its first
//! point, so errors never add up. The resulting accuracy is asserted by the tests below
//! against the ideal profile computed in f64.
//!
//! The profile is rebuilt from the present state when the planner's plan for the block
//! changes (a new block behind it, an override), and for feed hold (brake to rest,
//! possibly over several blocks) and resume. Hold keeps the rest of the path, so no
//! step is lost.
//!
//! Layers. This module is the block flow: it takes blocks from the planner, keeps the
//! one in execution (`Active`), decides when its profile is rebuilt (`Stale`, the
//! planner's generation) and runs feed hold and resume ([`HoldState`]). The profile's
//! evaluation and the choice of each segment are in `profile`, the integer per-tick
//! arithmetic and the queueing in `kernel`.
//!
//! A block's flow with a hold (speed against path position; `Prep.v_last` is the speed
//! at the last queued step, `Active.rest_q` the path left when the profile was built):
//!
//! ```text
//!   speed        hold()                               resume()
//!    ^             |  HoldState::Holding                 |  HoldState::Running
//!    |   +---------+                                     |         +------
//!    |  /          .\   (profile rebuilt to 0, Stale::Plan)|        /
//!    | /           . \                                   | /Stale::Profile: rebuilt
//!    |/            .  \         HoldState::Held           |/  from v_last = 0
//!    +-------------+---+-------------------------------- +----------------> path
//!    start_next()      at rest, rest of the path kept (Active.at.s < Active.rest_q)
//! ```

// `!(x > 0.0)` is meant throughout: a NaN must fail the test, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod kernel;
mod profile;
#[cfg(test)]
mod tests;

use super::{CmdSink, StepCmd};
use crate::interpolation::{Interpolator, Next, StepEvent};
use crate::motion::{StepPos, X, Y};
use crate::planner::profile::{Phase, Shape};
use crate::planner::{Block, Planner, PlannerConfig, Profile};
use kernel::*;
use profile::Cursor;

/// Feed-hold state: the one record of a hold, kept by the preparation (the
/// pipeline's motion state and its pen trip ask it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HoldState {
    Running,
    /// Braking to rest.
    Holding,
    /// At rest, with the rest of the path kept (in a block, or between blocks: no
    /// block starts until resumed).
    Held,
}

/// Step-engine timing parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PrepConfig {
    /// Step-timer clock, Hz.
    pub timer_hz: u32,
    /// Largest error the timing polynomials may add to a step's ideal time, seconds.
    pub max_error_s: f32,
}

impl Default for PrepConfig {
    fn default() -> Self {
        PrepConfig {
            timer_hz: 72_000_000,
            max_error_s: 0.5e-6,
        }
    }
}

/// A tick made but not yet queued (the queue was full, or a hold came to rest).
#[derive(Clone, Copy, Debug)]
enum Pending {
    /// Timed on its own: its length, Q units.
    StepEvent(StepEvent, u64),
    /// An extra step (no path length).
    Extra(StepEvent),
}

#[derive(Clone, Debug)]
struct Active {
    block: Block,
    interp: Interpolator,
    /// mm per unit of the interpolator's run (a line's tick, a circle's step).
    scale: f32,
    /// A line's tick in Q units: its ticks' positions are exact multiples of it.
    line_tick_q: Option<u64>,
    /// Length of the block left when the profile was built, Q units.
    rest_q: u64,
    /// The profile ends exactly at the last step of the path (a line's; an arc's once
    /// its last piece began in a cruise).
    exact_end: bool,
    prof: Profile,
    /// Timer counts of the phases' anchors: the profile's start, the cruise's start, the
    /// profile's end (the last ramp is timed back from it).
    anchors: [u64; 3],
    /// Where the phases end, Q units from the profile's start (the last is its length).
    ends_q: [u64; 3],
    /// Timer counts per mm in the cruise (one division per profile, not per segment).
    cruise_ticks_per_mm: f32,
    at: Cursor,
    /// Ticks left in the present run (0: ask the interpolator what comes next).
    run_left: u32,
    seg: Segment,
    pending: Option<Pending>,
}

/// The inner loop's working space: kept here rather than on the stack, so that no call
/// clears it.
#[derive(Clone, Debug)]
struct Batch {
    ticks: [StepEvent; BATCH],
    cmds: [StepCmd; BATCH],
}

/// The segment-preparation state.
#[derive(Clone, Debug)]
pub struct Prep {
    cfg: PrepConfig,
    batch: Batch,
    active: Option<Active>,
    /// Timer tick of the last queued step.
    t_last: u64,
    /// Path speed at that step, mm/s.
    v_last: f32,
    generation: u32,
    /// Whether the profile must be looked at again although the planner's generation
    /// did not change.
    stale: Stale,
    hold: HoldState,
    /// Where the next block starts: the end of the last one (or where the machine was
    /// set to).
    pos: StepPos,
    /// Blocks whose interpolation was rejected (skipped without moving).
    skipped: u32,
    /// Wait before the last queued step, timer counts.
    last_wait: u32,
    /// The speed limit and exit speed the present profile was built for.
    planned: (f32, f32),
}

/// Why the profile is to be looked at again besides a new plan (the planner's generation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Stale {
    /// Only if the planner's generation changed.
    Fresh,
    /// Re-read the planner's speed limit and exit speed (a hold began): rebuild if they
    /// differ from the profile's.
    Plan,
    /// Rebuild the profile from the present state whatever the speeds (a block began, a
    /// resume, an arc's last piece whose exact end is now known).
    Profile,
}

/// What [`Prep::advance`] set up.
enum Ready {
    /// A segment of the present run.
    Segment,
    /// One tick to time on its own.
    Single,
    /// The block is done, or its profile is to be rebuilt first.
    Finished,
}

impl Prep {
    pub fn new(cfg: PrepConfig, position: StepPos) -> Self {
        Prep {
            cfg,
            batch: Batch {
                ticks: [StepEvent(0); BATCH],
                cmds: [StepCmd(0); BATCH],
            },
            active: None,
            t_last: 0,
            v_last: 0.0,
            generation: 0,
            stale: Stale::Fresh,
            hold: HoldState::Running,
            pos: position,
            skipped: 0,
            last_wait: u32::MAX,
            planned: (0.0, 0.0),
        }
    }

    pub fn hold_state(&self) -> HoldState {
        self.hold
    }
    /// Nothing in execution and nothing left to prepare.
    pub fn is_idle(&self, planner: &Planner) -> bool {
        self.active.is_none() && planner.is_empty()
    }
    /// Path speed at the last prepared step, mm/s: the block in execution's cursor,
    /// which segments move too (a run of steps prepared as one segment leaves no
    /// single tick behind to say its speed), else the speed the last block ended at.
    pub fn speed(&self) -> f32 {
        match &self.active {
            Some(a) => a.at.v,
            None => self.v_last,
        }
    }
    pub fn skipped(&self) -> u32 {
        self.skipped
    }
    /// Source line of the block in execution.
    pub fn line(&self) -> Option<u32> {
        self.active.as_ref().map(|a| a.block.mv.line)
    }
    /// Timer counts from the preparation's epoch to its last prepared step command
    /// (what it has queued takes the time between two readings).
    pub fn prepared_until(&self) -> u64 {
        self.t_last
    }
    /// The wait of the last prepared step command, timer counts.
    pub fn last_wait(&self) -> u32 {
        self.last_wait
    }
    /// Step commands that cover `ticks` timer counts at the present step rate (integer:
    /// how far ahead of the interrupt to prepare).
    pub fn commands_for(&self, ticks: u32) -> usize {
        (ticks / self.last_wait.max(1)) as usize
    }

    /// Feed hold: brake to rest as fast as the limits allow; between blocks, start
    /// none until resumed.
    pub fn hold(&mut self) {
        if self.hold != HoldState::Running {
            return;
        }
        if self.active.is_some() {
            self.hold = HoldState::Holding;
            self.stale = self.stale.max(Stale::Plan);
        } else {
            self.hold = HoldState::Held;
        }
    }

    /// A block is in execution (the hold, if any, is within it).
    pub fn in_block(&self) -> bool {
        self.active.is_some()
    }

    /// Cycle start after a hold.
    pub fn resume(&mut self, planner: &mut Planner) {
        if self.hold == HoldState::Held || self.hold == HoldState::Holding {
            self.hold = HoldState::Running;
            if let Some(a) = self.active.as_ref() {
                // From rest (or the speed the hold left) with the rest of the block
                // ahead: the planner decides how fast it may now be left.
                let rest = from_q(a.rest_q.saturating_sub(a.at.s));
                planner.head_runs(&a.block, self.v_last, rest);
            }
            self.stale = Stale::Profile;
        }
    }

    /// Drops the block in execution (after an emergency stop or a reset); `position`
    /// is where the machine really is (the executor's count).
    pub fn abort(&mut self, position: StepPos) {
        self.active = None;
        self.hold = HoldState::Running;
        self.v_last = 0.0;
        self.pos = position;
    }

    /// Prepares up to `limit` commands (fewer if `sink` fills up, the path ends, or a
    /// hold comes to rest): the tests' call; the pipeline bounds its calls in time.
    #[cfg(test)]
    pub fn fill(&mut self, planner: &mut Planner, sink: &mut dyn CmdSink, limit: usize) {
        self.fill_until(planner, sink, limit, limit, u64::MAX);
    }

    /// Prepares at least `at_least` and at most `at_most` commands (fewer if `sink`
    /// fills up, the path ends, or a hold comes to rest), and beyond `at_least` only
    /// while the prepared steps end before `until` ([`Prep::prepared_until`]'s
    /// timeline): a count from the last wait ([`Prep::commands_for`]) overshoots
    /// after a short wait among long ones (see the pipeline's `fill_queue`). `dyn`:
    /// one copy compiled in the core (size-optimised), not one per caller; the sink
    /// takes a batch per call.
    pub fn fill_until(
        &mut self,
        planner: &mut Planner,
        sink: &mut dyn CmdSink,
        at_least: usize,
        at_most: usize,
        until: u64,
    ) {
        let mut room = sink.room().min(at_most);
        let enough = room.saturating_sub(at_least);
        while room > 0 {
            if room <= enough && self.t_last >= until {
                return;
            }
            if self.hold == HoldState::Held {
                return;
            }
            if self.active.is_none() && !self.start_next(planner) {
                return;
            }
            if planner.generation() != self.generation || self.stale != Stale::Fresh {
                self.replan(planner);
            }
            let Some(a) = self.active.as_mut() else {
                return;
            };
            let Batch { ticks, cmds } = &mut self.batch;
            if a.seg.left == 0 {
                match self.advance() {
                    Ready::Segment | Ready::Finished => {}
                    Ready::Single => match self.single(planner.config(), sink, room) {
                        Some(used) => room -= used,
                        None => return,
                    },
                }
                continue;
            }
            // The inner loop: make a batch of the segment's ticks, time them (a few
            // additions each) and queue them in one go.
            let n = room.min(BATCH).min(a.seg.left as usize);
            let got = a.interp.events_into(&mut ticks[..n]);
            if got < n {
                // A run never ends early; should it, the block ends after these ticks.
                a.seg.left = got as u32;
                a.run_left = got as u32;
            }
            a.seg.time(&ticks[..got], &mut cmds[..got]);
            a.run_left -= got as u32;
            sink.push_slice(&cmds[..got]);
            self.t_last = a.seg.base.wrapping_add(u64::from(a.seg.at));
            if let Some(last) = cmds[..got].last() {
                self.last_wait = last.wait();
            }
            room -= got;
        }
    }
}

impl Prep {
    /// Takes the next block from the planner and sets up its interpolation; its profile
    /// follows from the plan ([`Prep::replan`]).
    #[inline(never)]
    fn start_next(&mut self, planner: &mut Planner) -> bool {
        loop {
            let Some(block) = planner.pop() else {
                planner.note_stopped();
                if self.hold == HoldState::Holding {
                    self.hold = HoldState::Held;
                }
                return false;
            };
            let cfg = planner.config();
            let interp = match Interpolator::new(self.pos, &block.mv, cfg.method) {
                Ok(i) => i,
                Err(_) => {
                    self.skipped = self.skipped.wrapping_add(1);
                    continue;
                }
            };
            let (scale, line_tick_q, len_q) = match &interp {
                Interpolator::Line(l) => {
                    // Every tick of a line covers the same length (of the length the
                    // planner planned): its positions are exact multiples, and the last
                    // lands on the block's end.
                    let ticks = l.ticks().max(1);
                    let per = block.length / ticks as f32;
                    let q = to_q(per);
                    (per, Some(q), q.wrapping_mul(ticks))
                }
                _ => (
                    1.0 / cfg.axes[X].steps_per_mm.max(1e-6),
                    None,
                    to_q(block.length),
                ),
            };
            let shape = cfg.shape;
            let v = self.v_last;
            // The block starts at the speed the last one left at: the planner
            // decides how fast it may be left.
            planner.head_runs(&block, v, block.length);
            self.active = Some(Active {
                block,
                interp,
                scale,
                line_tick_q,
                rest_q: len_q,
                exact_end: line_tick_q.is_some(),
                prof: Profile::rest(shape),
                anchors: [self.t_last; 3],
                ends_q: [0; 3],
                cruise_ticks_per_mm: 0.0,
                at: Cursor {
                    s: 0,
                    phase: Phase::Up,
                    t: 0.0,
                    at: self.t_last,
                    v,
                    rate: 1.0,
                },
                run_left: 0,
                seg: Segment::default(),
                pending: None,
            });
            self.stale = Stale::Profile;
            return true;
        }
    }

    /// The plan changed (or the block just began, or a hold or resume): if this block's
    /// speed limit or exit speed changed, a new profile from the last queued tick.
    #[inline(never)]
    fn replan(&mut self, planner: &Planner) {
        self.generation = planner.generation();
        let rebuild = self.stale == Stale::Profile;
        self.stale = Stale::Fresh;
        let hz = self.cfg.timer_hz as f32;
        let Some(a) = self.active.as_mut() else {
            return;
        };
        let running = self.hold == HoldState::Running;
        // A block never runs above its own speed: not to reach the next block's entry,
        // nor from the start rate ($213 lets a move start at once up to that rate; a
        // slower move runs at its own feed).
        let planned = if running {
            let v_max = planner.max_speed(&a.block);
            (v_max, planner.exit_speed().min(v_max))
        } else {
            (0.0, 0.0)
        };
        if planned == self.planned && !rebuild {
            return;
        }
        self.planned = planned;
        let cfg = planner.config();
        let (s_now, v_now, t0) = a.now(self.t_last);
        let v0 = if running {
            v_now.max(cfg.start_speed.min(planned.0))
        } else {
            v_now
        };
        let rest_q = a.rest_q.saturating_sub(s_now);
        let rest = from_q(rest_q);
        let prof = Profile::new(cfg.shape, v0, planned.0, planned.1, a.block.accel, rest);
        let (e0, e1, distance) = prof.phase_ends_and_distance();
        // A profile that covers the block ends exactly on its end (a line's last tick).
        let end_q = if distance >= rest * (1.0 - 1e-6) {
            rest_q
        } else {
            to_q(distance)
        };
        let (v_cruise, _) = prof.phase_speeds(Phase::Cruise);
        a.cruise_ticks_per_mm = if v_cruise > 0.0 { hz / v_cruise } else { 0.0 };
        let d = prof.phase_durations();
        let ticks = |t: f32| (t * hz + 0.5) as u64;
        a.anchors = [t0, t0 + ticks(d[0]), t0 + ticks(d[0] + d[1] + d[2])];
        a.ends_q = [to_q(e0).min(end_q), to_q(e1).min(end_q), end_q];
        a.rest_q = rest_q;
        a.prof = prof;
        let rate = if a.seg.left > 0 {
            a.interp.path_ahead(0).1
        } else {
            a.at.rate
        };
        a.at = Cursor {
            s: 0,
            phase: Phase::Up,
            t: 0.0,
            at: t0,
            v: v0,
            rate,
        };
        a.seg.left = 0;
    }

    /// With no segment in progress: sets up the next one, or says that a tick is to be
    /// timed on its own, or finishes the block.
    fn advance(&mut self) -> Ready {
        let eps = self.cfg.max_error_s;
        let hz = self.cfg.timer_hz as f32;
        let Some(a) = self.active.as_mut() else {
            return Ready::Finished;
        };
        if a.pending.is_some() {
            return Ready::Single;
        }
        if a.run_left == 0 {
            match a.interp.next() {
                Next::Run(n) => {
                    a.run_left = n;
                    // The cursor moves by the shift along the path (and in time, with
                    // its speed, exactly): the new run's ticks follow from there.
                    let shift = a.interp.entry_shift() * a.scale;
                    if shift != 0.0 && a.at.v > 0.0 {
                        let s = if shift > 0.0 {
                            a.at.s + to_q(shift)
                        } else {
                            a.at.s.saturating_sub(to_q(-shift))
                        };
                        if let Some(p) = a.phase_of(s) {
                            a.at = a.exact(p, s, hz);
                        }
                    }
                    a.at.rate = a.interp.path_ahead(0).1;
                    let memoryless = match a.at.phase {
                        Phase::Cruise => true,
                        Phase::Up => a.prof.shape() == Shape::Trapezoid || a.at.s == 0,
                        Phase::Down => false,
                    };
                    let d = a.interp.path_ahead(n).0;
                    let end_q = a.at.s + to_q(d * a.scale);
                    // The last ramp must still lie ahead, with a step to spare.
                    let ramp_q = a.ends_q[2] - a.ends_q[1];
                    let room = end_q.saturating_sub(a.at.s) > ramp_q + to_q(a.scale * 2.0);
                    if a.interp.in_last_run() && memoryless && room {
                        // An arc's last piece: its steps' path is now known to the end, so
                        // the profile is rebuilt to end exactly at its last step (the
                        // planned length differs by rounding, and near rest a step's time
                        // is most sensitive to its position). Only where a profile rebuilt
                        // from the present state is the same (in a cruise, or a
                        // trapezoid's first ramp, with the last ramp still ahead): an
                        // S-curve's ramp or a last ramp about to begin keep the planned
                        // length, and a last step beyond it comes at its end.
                        a.rest_q = end_q;
                        a.exact_end = true;
                        self.stale = Stale::Profile;
                        return Ready::Finished;
                    }
                }
                Next::StepEvent | Next::Extra => return Ready::Single,
                Next::Done => {
                    self.finish();
                    return Ready::Finished;
                }
            }
        }
        match a.plan_segment(eps, hz, self.t_last) {
            true => Ready::Segment,
            false => Ready::Single,
        }
    }

    /// The block in execution is done: the next starts where it ended.
    fn finish(&mut self) {
        if let Some(a) = self.active.take() {
            self.pos = a.block.mv.target;
            self.v_last = a.at.v;
        }
    }

    /// Makes, times and queues one tick on its own (a tick with a length, an extra step,
    /// a run's tick beyond the profile's end). The commands used (pure waits first for
    /// a slow one; 0 when the block ended), `None` when nothing more can be done now
    /// (the queue is full, or a hold came to rest).
    fn single(
        &mut self,
        cfg: &PlannerConfig,
        sink: &mut dyn CmdSink,
        room: usize,
    ) -> Option<usize> {
        let hz = self.cfg.timer_hz as f32;
        let spm = [cfg.axes[X].steps_per_mm, cfg.axes[Y].steps_per_mm];
        let a = self.active.as_mut()?;
        let pending = match a.pending.take() {
            Some(p) => p,
            None => {
                let mut one = [StepEvent(0)];
                let kind = if a.run_left > 0 {
                    Next::Run(a.run_left)
                } else {
                    a.interp.next()
                };
                if a.interp.events_into(&mut one) == 0 {
                    self.finish();
                    return Some(0);
                }
                match kind {
                    Next::Run(_) => {
                        a.run_left -= 1;
                        let q = match a.line_tick_q {
                            Some(q) => q,
                            None => to_q(a.interp.path_ahead(0).1 * a.scale),
                        };
                        Pending::StepEvent(one[0], q)
                    }
                    Next::StepEvent => Pending::StepEvent(one[0], to_q(a.interp.tick_len(spm))),
                    _ => Pending::Extra(one[0]),
                }
            }
        };
        // Its time.
        let (tick, at, cursor) = match pending {
            Pending::Extra(tick) => (tick, self.t_last + u64::from(self.last_wait / 2), None),
            Pending::StepEvent(tick, len_q) => {
                let s1 = a.at.s + len_q;
                match a.phase_of(s1) {
                    Some(p) => {
                        let c = a.exact(p, s1, hz);
                        (tick, c.at, Some(c))
                    }
                    None => {
                        if self.hold != HoldState::Running && a.prof.exit_speed() < 1e-3 {
                            // A hold came to rest before this tick: it waits for resume.
                            a.pending = Some(pending);
                            self.hold = HoldState::Held;
                            self.v_last = 0.0;
                            return None;
                        }
                        // Beyond the profile's end (an arc's length rounding): at its end, or
                        // on at the last rate once that has passed.
                        let end = a.anchors[2];
                        let at = if end > self.t_last {
                            end
                        } else {
                            self.t_last + u64::from(self.last_wait)
                        };
                        (tick, at, None)
                    }
                }
            }
        };
        // No step comes sooner than the event cap allows after the last one
        // (a classic tick across the circle's radius has almost no path length; a
        // catch-up step is timed off the last wait): later steps keep their profile
        // times, so the delay is made up where the profile leaves room.
        let wait = at
            .saturating_sub(self.t_last)
            .max(min_wait(self.cfg.timer_hz, cfg.max_event_rate));
        let needed = commands_for_wait(wait);
        if needed > room {
            a.pending = Some(pending);
            return None;
        }
        self.last_wait = push_waited(sink, tick, wait);
        self.t_last += wait;
        if let Some(c) = cursor {
            a.at = Cursor {
                rate: a.at.rate,
                ..c
            };
            self.v_last = c.v;
        }
        Some(needed)
    }
}
