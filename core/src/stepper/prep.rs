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
//! in integers (`Ramp`), other ramps take shorter segments, and the first tick of a
//! phase (or from rest) its own. Every segment starts on the exact time of its first
//! point, so errors never add up. The resulting accuracy is asserted by the tests below
//! against the ideal profile computed in f64.
//!
//! The profile is rebuilt from the present state when the planner's plan for the block
//! changes (a new block behind it, an override), and for feed hold (brake to rest,
//! possibly over several blocks) and resume. Hold keeps the rest of the path, so no
//! step is lost.

// `!(x > 0.0)` is meant throughout: a NaN must fail the test, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{CmdSink, StepCmd, MAX_STEP_RATE, MAX_WAIT};
use crate::interpolation::{Interpolator, Next, Tick};
use crate::motion::{StepPos, X, Y};
use crate::planner::profile::{Phase, Shape};
use crate::planner::{Block, Planner, PlannerConfig, Profile};

/// Feed-hold state of the preparation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HoldState {
    Running,
    /// Braking to rest.
    Holding,
    /// At rest, with the rest of the path kept.
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

/// Distance unit of path positions: 2^-32 mm.
const Q: f32 = 4_294_967_296.0;
/// Longest segment whose time is not linear in the tick count, ticks.
const MAX_SEGMENT: u32 = 256;
/// Longest segment whose time is linear in the tick count, ticks.
const MAX_LINEAR: u32 = 2048;
/// Ticks timed per pass of the inner loop (a stack buffer of ticks and commands).
const BATCH: usize = 32;
/// Longest segment, timer ticks (its time since the segment start stays in i64 with 32
/// fractional bits).
const MAX_SEGMENT_TICKS: f32 = 1.0e9;

/// The ticks of one segment and how they are timed; `base` is the timer tick of the
/// segment's start and `at` the last queued tick's time since it (a segment lasts less
/// than 2^30 timer ticks, so 32 bits hold it).
#[derive(Clone, Copy, Debug, Default)]
struct Segment {
    left: u32,
    timing: Timing,
    base: u64,
    at: u32,
}

/// How a segment's ticks get their times.
#[derive(Clone, Copy, Debug)]
enum Timing {
    /// A polynomial in the tick count: `acc` is the time since the segment's start and
    /// `d1..d3` its forward differences, in timer ticks with 32 fractional bits;
    /// `linear` when d2 = d3 = 0.
    Poly {
        acc: u64,
        d1: u64,
        d2: u64,
        d3: u64,
        linear: bool,
    },
    /// A constant acceleration along a line, exact: see [`Ramp`].
    Ramp(Ramp),
}

impl Default for Timing {
    fn default() -> Self {
        Timing::Poly {
            acc: 0,
            d1: 0,
            d2: 0,
            d3: 0,
            linear: true,
        }
    }
}

/// Tick times under constant acceleration, in integers. With R = v / a in timer ticks
/// (the time the speed would take to reach 0), R^2 = W grows or falls by 2 ds / a
/// (ticks^2) per tick of length ds, and the tick's time is a fixed tick plus or minus R
/// (the ramp's anchor: its start, or the profile's end for the last ramp). Each tick
/// updates W by one addition and takes R = floor(sqrt W) from the last two differences
/// of R (quadratic extrapolation) and one Newton correction with a 32-bit division, then
/// checks it exactly (one 32x32 multiply each way). Near rest the guess can be far off:
/// the exact digit-by-digit root there. Every time is the exact one rounded down to the
/// timer tick (up to f32 rounding of W's start and step).
#[derive(Clone, Copy, Debug)]
struct Ramp {
    /// W and its forward differences per tick (wrapping: the differences may be
    /// negative). A line's ticks are equal, so W moves by a constant; along a curve the
    /// path position is a cubic in the tick count (within the error bound), so W is too.
    w: u64,
    dw1: u64,
    dw2: u64,
    dw3: u64,
    /// The tick's time since the segment's start is r0 + R (rising) or r0 - R.
    rising_t: bool,
    r0: u32,
    r: u32,
    dr: i32,
    ddr: i32,
}

impl Ramp {
    /// floor(sqrt(w)) near the guess `g` (below 2^30): one Newton step from the guess
    /// with a 32-bit division, checked exactly; far from it (near rest), digit by digit.
    #[inline(always)]
    fn root_near(w: u64, g: u32) -> u32 {
        if (w as i64) < 0 {
            // W fell below 0 (a curve's cubic just past rest): at rest.
            return 0;
        }
        let g = g.clamp(1, (1 << 30) - 1);
        let e = w as i64 - (u64::from(g) * u64::from(g)) as i64;
        if e.unsigned_abs() < 1 << 31 {
            let r = (g as i32 + (e as i32) / (2 * g as i32)).max(1) as u64;
            // r^2 <= w < (r + 1)^2, or one step either way.
            let sq = r * r;
            if sq <= w {
                if sq + 2 * r + 1 > w {
                    return r as u32;
                }
                if sq + 4 * r + 4 > w {
                    return r as u32 + 1;
                }
            } else if (r - 1) * (r - 1) <= w {
                return r as u32 - 1;
            }
        }
        crate::fmath::isqrt(w) as u32
    }

    /// The next tick's time since the segment's start (32 bits, wrapping).
    #[inline(always)]
    fn next(&mut self) -> u32 {
        self.w = self.w.wrapping_add(self.dw1);
        self.dw1 = self.dw1.wrapping_add(self.dw2);
        self.dw2 = self.dw2.wrapping_add(self.dw3);
        let guess = (self.r as i32).wrapping_add(self.dr).wrapping_add(self.ddr);
        let r = Self::root_near(self.w, guess.max(1) as u32);
        let dr = r.wrapping_sub(self.r) as i32;
        self.ddr = dr.wrapping_sub(self.dr);
        self.dr = dr;
        self.r = r;
        if self.rising_t {
            self.r0.wrapping_add(r)
        } else {
            self.r0.wrapping_sub(r)
        }
    }
}

impl Segment {
    /// `n` ticks timed by a polynomial with the forward differences `d` (timer ticks,
    /// see [`fixed`]) from the cursor's time `base`; `t_last` is the last queued tick's.
    fn poly(n: u32, d: [i64; 3], base: u64, t_last: u64) -> Self {
        let [d1, d2, d3] = d.map(|d| d as u64);
        Segment {
            left: n,
            timing: Timing::Poly {
                acc: 0,
                d1,
                d2,
                d3,
                linear: d2 == 0 && d3 == 0,
            },
            base,
            at: t_last.wrapping_sub(base) as u32,
        }
    }

    /// Times `ticks` and packs them into `cmds` (the same length): per tick two
    /// (linear) or six (cubic) 32-bit additions, or a ramp's integer root, and the wait
    /// since the last one.
    #[inline(always)]
    fn time(&mut self, ticks: &[Tick], cmds: &mut [StepCmd]) {
        let mut prev = self.at;
        let mut emit = |at: u32, tick: Tick, cmd: &mut StepCmd| {
            // At least 2 ticks apart (the executor's promise); the 24-bit bound holds
            // for every segment (a tick that may wait longer is timed on its own).
            let wait = at.wrapping_sub(prev).clamp(2, MAX_WAIT);
            prev = prev.wrapping_add(wait);
            *cmd = StepCmd((u32::from(tick.0) << 24) | wait);
        };
        match &mut self.timing {
            Timing::Poly {
                acc,
                d1,
                linear: true,
                ..
            } => {
                let (mut a, d) = (*acc, *d1);
                for (tick, cmd) in ticks.iter().zip(cmds.iter_mut()) {
                    a = a.wrapping_add(d);
                    emit((a >> 32) as u32, *tick, cmd);
                }
                *acc = a;
            }
            Timing::Poly {
                acc, d1, d2, d3, ..
            } => {
                let (mut a, mut b, mut c, d) = (*acc, *d1, *d2, *d3);
                for (tick, cmd) in ticks.iter().zip(cmds.iter_mut()) {
                    a = a.wrapping_add(b);
                    b = b.wrapping_add(c);
                    c = c.wrapping_add(d);
                    emit((a >> 32) as u32, *tick, cmd);
                }
                (*acc, *d1, *d2) = (a, b, c);
            }
            Timing::Ramp(ramp) => {
                for (tick, cmd) in ticks.iter().zip(cmds.iter_mut()) {
                    emit(ramp.next(), *tick, cmd);
                }
            }
        }
        self.at = prev;
        self.left -= ticks.len() as u32;
    }
}

/// Where the profile stands at the last timed tick (the end of the present segment).
#[derive(Clone, Copy, Debug)]
struct Cursor {
    /// Path position, Q units from the profile's start.
    s: u64,
    /// Its phase, the phase-local time there (see [`Profile::phase_time`]), seconds,
    /// and the timer tick it falls on.
    phase: Phase,
    t: f32,
    at: u64,
    /// Speed there, mm/s.
    v: f32,
    /// The run's rate there, run units per tick.
    rate: f32,
}

/// A tick made but not yet queued (the queue was full, or a hold came to rest).
#[derive(Clone, Copy, Debug)]
enum Pending {
    /// Timed on its own: its length, Q units.
    Tick(Tick, u64),
    /// An extra step (no path length).
    Extra(Tick),
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
    /// Timer ticks of the phases' anchors: the profile's start, the cruise's start, the
    /// profile's end (the last ramp is timed back from it).
    anchors: [u64; 3],
    /// Where the phases end, Q units from the profile's start (the last is its length).
    ends_q: [u64; 3],
    /// Timer ticks per mm in the cruise (one division per profile, not per segment).
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
    ticks: [Tick; BATCH],
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
    hold: HoldState,
    /// Where the next block starts: the end of the last one (or where the machine was
    /// set to).
    pos: StepPos,
    /// Blocks whose interpolation was rejected (skipped without moving).
    skipped: u32,
    /// Wait before the last queued step, timer ticks.
    last_wait: u32,
    /// The speed limit and exit speed the present profile was built for.
    planned: (f32, f32),
}

fn to_q(mm: f32) -> u64 {
    if mm > 0.0 {
        (mm * Q + 0.5) as u64
    } else {
        0
    }
}

fn from_q(q: u64) -> f32 {
    q as f32 * (1.0 / Q)
}

/// f32 timer ticks (at most 2^31) in i64 with 32 fractional bits.
fn fixed(ticks: f32) -> i64 {
    (ticks * Q) as i64
}

/// The forward differences of the cubic Hermite polynomial through (0, 0) and
/// (n, span) with the slopes `m0` and `m1` at its ends (per tick).
fn hermite(n: u32, span: f32, m0: f32, m1: f32) -> [f32; 3] {
    let nf = n as f32;
    let inv = 1.0 / nf;
    let c3 = ((m0 + m1) * nf - 2.0 * span) * inv * inv * inv;
    let c2 = (3.0 * span - (2.0 * m0 + m1) * nf) * inv * inv;
    [c3 + c2 + m0, 6.0 * c3 + 2.0 * c2, 6.0 * c3]
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
                ticks: [Tick(0); BATCH],
                cmds: [StepCmd(0); BATCH],
            },
            active: None,
            t_last: 0,
            v_last: 0.0,
            generation: 0,
            hold: HoldState::Running,
            pos: position,
            skipped: 0,
            last_wait: u32::MAX,
            planned: (-1.0, -1.0),
        }
    }

    pub fn hold_state(&self) -> HoldState {
        self.hold
    }
    /// No block in execution (at rest between blocks, or idle).
    pub fn is_idle_block(&self) -> bool {
        self.active.is_none() && self.v_last <= 0.0
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
    /// Step commands that cover `ticks` timer ticks at the present step rate (integer:
    /// how far ahead of the interrupt to prepare).
    pub fn commands_for(&self, ticks: u32) -> usize {
        (ticks / self.last_wait.max(1)) as usize
    }

    /// Feed hold: brake to rest as fast as the limits allow.
    pub fn hold(&mut self) {
        if self.hold == HoldState::Running && self.active.is_some() {
            self.hold = HoldState::Holding;
            self.generation = self.generation.wrapping_sub(1);
        }
    }

    /// Cycle start after a hold.
    pub fn resume(&mut self, planner: &mut Planner) {
        if self.hold == HoldState::Held || self.hold == HoldState::Holding {
            self.hold = HoldState::Running;
            if let Some(a) = self.active.as_ref() {
                let ae = planner.plan_accel(&a.block);
                let rest = from_q(a.rest_q.saturating_sub(a.at.s));
                planner.set_head_cap(crate::fmath::sqrt(
                    self.v_last * self.v_last + 2.0 * ae * rest,
                ));
            }
            self.generation = planner.generation().wrapping_sub(1);
            self.planned = (-1.0, -1.0);
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
    /// hold comes to rest). `dyn`: one copy compiled in the core (size-optimised), not
    /// one per caller; the sink takes a batch per call.
    pub fn fill(&mut self, planner: &mut Planner, sink: &mut dyn CmdSink, limit: usize) {
        let mut room = sink.room().min(limit);
        while room > 0 {
            if self.hold == HoldState::Held {
                return;
            }
            if self.active.is_none() && !self.start_next(planner) {
                return;
            }
            if planner.generation() != self.generation {
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
            let got = a.interp.ticks_into(&mut ticks[..n]);
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
            let ae = planner.plan_accel(&block);
            let v = self.v_last;
            planner.set_head_cap(crate::fmath::sqrt(v * v + 2.0 * ae * block.length));
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
            self.generation = planner.generation().wrapping_sub(1);
            self.planned = (-1.0, -1.0);
            return true;
        }
    }

    /// The plan changed (or the block just began, or a hold or resume): if this block's
    /// speed limit or exit speed changed, a new profile from the last queued tick.
    #[inline(never)]
    fn replan(&mut self, planner: &Planner) {
        self.generation = planner.generation();
        let hz = self.cfg.timer_hz as f32;
        let Some(a) = self.active.as_mut() else {
            return;
        };
        let running = self.hold == HoldState::Running;
        let planned = if running {
            (planner.max_speed(&a.block), planner.exit_speed())
        } else {
            (0.0, 0.0)
        };
        if planned == self.planned {
            return;
        }
        self.planned = planned;
        let cfg = planner.config();
        let (s_now, v_now, t0) = a.now(self.t_last);
        let v0 = if running {
            v_now.max(cfg.start_speed)
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
                        self.planned = (-1.0, -1.0);
                        self.generation = self.generation.wrapping_sub(1);
                        return Ready::Finished;
                    }
                }
                Next::Tick | Next::Extra => return Ready::Single,
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
                let mut one = [Tick(0)];
                let kind = if a.run_left > 0 {
                    Next::Run(a.run_left)
                } else {
                    a.interp.next()
                };
                if a.interp.ticks_into(&mut one) == 0 {
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
                        Pending::Tick(one[0], q)
                    }
                    Next::Tick => Pending::Tick(one[0], to_q(a.interp.tick_len(spm))),
                    _ => Pending::Extra(one[0]),
                }
            }
        };
        // Its time.
        let (tick, at, cursor) = match pending {
            Pending::Extra(tick) => (tick, self.t_last + u64::from(self.last_wait / 2), None),
            Pending::Tick(tick, len_q) => {
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
        // No step comes sooner than the step pipeline's cap allows after the last one
        // (a classic tick across the circle's radius has almost no path length; a
        // catch-up step is timed off the last wait): later steps keep their profile
        // times, so the delay is made up where the profile leaves room.
        let wait = at
            .saturating_sub(self.t_last)
            .max(min_wait(self.cfg.timer_hz));
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

/// The shortest wait between two step events, timer ticks: one event period at the
/// step pipeline's cap ([`MAX_STEP_RATE`], 12.5 us), longer than any step pulse plus
/// the drivers' low time.
fn min_wait(timer_hz: u32) -> u64 {
    let w = timer_hz as f32 / MAX_STEP_RATE;
    (w as u64 + u64::from((w as u64 as f32) < w)).max(2)
}

/// Whole ticks of `q` in `len` (Q units): the division in f32, checked exactly.
fn ticks_in(len: u64, q: u64) -> u64 {
    let q = q.max(1);
    let mut n = (len as f32 / q as f32) as u64;
    while n > 0 && n.wrapping_mul(q) > len {
        n -= 1;
    }
    while (n + 1).wrapping_mul(q) <= len {
        n += 1;
    }
    n
}

/// Pure waits before a step whose wait is longer than a command holds: each this long
/// (a power of two, so that counting them is a shift, not a 64-bit division).
const PURE_WAIT: u64 = 1 << 23;

/// Pure waits a step `wait` ticks after the last one needs before its own command.
fn pure_waits(wait: u64) -> u64 {
    if wait > u64::from(MAX_WAIT) {
        (wait - u64::from(MAX_WAIT) + PURE_WAIT - 1) >> 23
    } else {
        0
    }
}

/// Commands a step `wait` ticks after the last one takes.
fn commands_for_wait(wait: u64) -> usize {
    1 + pure_waits(wait) as usize
}

/// Queues `tick` `wait` ticks after the last command (pure waits first for a long
/// one); the wait of its own command.
fn push_waited(sink: &mut dyn CmdSink, tick: Tick, wait: u64) -> u32 {
    let n = pure_waits(wait);
    for _ in 0..n {
        sink.push_slice(&[StepCmd::new(Tick(0), PURE_WAIT as u32)]);
    }
    let last = wait.max(2) - n * PURE_WAIT;
    sink.push_slice(&[StepCmd::new(tick, last as u32)]);
    last as u32
}

impl Active {
    /// Path position, speed and time of the present point: the cursor between
    /// segments (it may lie a little off the last queued tick's time after a circle's
    /// change of coordinate, see [`Interpolator::entry_shift`]), else the last queued
    /// tick (`t_last`).
    fn now(&self, t_last: u64) -> (u64, f32, u64) {
        if self.seg.left == 0 {
            return (self.at.s, self.at.v, self.at.at);
        }
        let ahead = match self.line_tick_q {
            Some(q) => q.wrapping_mul(u64::from(self.seg.left)),
            None => to_q(self.interp.path_ahead(self.seg.left).0 * self.scale),
        };
        let s = self.at.s.saturating_sub(ahead);
        let p = self.phase_of(s).unwrap_or(Phase::Down);
        let (_, v) = self.prof.phase_time(p, self.local(p, s), self.at.t);
        (s, v, t_last)
    }

    /// Path position (Q units from the profile's start) and the run's rate `n` ticks
    /// ahead: a line's exact multiple; a curve's from the interpolator, and at the end
    /// of an arc's last run exactly the profile's end (the same point, without the
    /// rounding of the sum).
    fn ahead(&self, n: u32) -> (u64, f32) {
        if let Some(q) = self.line_tick_q {
            return (self.at.s + q.wrapping_mul(u64::from(n)), 1.0);
        }
        let (d, r) = self.interp.path_ahead(n);
        if n == self.run_left && self.exact_end && self.interp.in_last_run() {
            return (self.rest_q.max(self.at.s), r);
        }
        (self.at.s + to_q(d * self.scale), r)
    }

    /// The phase a tick at path position `s` falls in (`None`: beyond the profile).
    fn phase_of(&self, s: u64) -> Option<Phase> {
        if s <= self.ends_q[0] && self.ends_q[0] > 0 {
            Some(Phase::Up)
        } else if s <= self.ends_q[1] && self.ends_q[1] > self.ends_q[0] {
            Some(Phase::Cruise)
        } else if s <= self.ends_q[2] {
            Some(Phase::Down)
        } else {
            None
        }
    }

    /// The phase-local distance of position `s` (see [`Profile::phase_time`]).
    fn local(&self, p: Phase, s: u64) -> f32 {
        match p {
            Phase::Up => from_q(s),
            Phase::Cruise => from_q(s.saturating_sub(self.ends_q[0])),
            Phase::Down => from_q(self.ends_q[2].saturating_sub(s)),
        }
    }

    /// The exact time of position `s` in phase `p`: the cursor there.
    fn exact(&self, p: Phase, s: u64, hz: f32) -> Cursor {
        let (t, v, ticks) = if p == Phase::Cruise {
            // The cruise's time is its distance over its speed: a product here (the
            // phase-local time, a hint for Newton's method elsewhere, is not needed).
            let ticks = self.local(p, s) * self.cruise_ticks_per_mm;
            (0.0, self.prof.phase_speeds(p).0, ticks)
        } else {
            let hint = if p == self.at.phase { self.at.t } else { 0.0 };
            let (t, v) = self.prof.phase_time(p, self.local(p, s), hint);
            (t, v, t * hz)
        };
        let ticks = (ticks + 0.5) as u64;
        let at = match p {
            Phase::Up => self.anchors[0] + ticks,
            Phase::Cruise => self.anchors[1] + ticks,
            Phase::Down => self.anchors[2].saturating_sub(ticks),
        };
        Cursor {
            s,
            phase: p,
            t,
            at,
            v,
            rate: self.at.rate,
        }
    }

    /// Sets up the next segment of the present run: `false` if the next tick is to be
    /// timed on its own (it lies beyond the profile's end).
    fn plan_segment(&mut self, eps: f32, hz: f32, t_last: u64) -> bool {
        let at = self.at;
        let step_q = match self.line_tick_q {
            Some(q) => q,
            None => to_q(at.rate * self.scale),
        };
        // The next tick's phase, from the rate (near the end exactly: a curve's last
        // tick lands on the profile's end).
        let near = self
            .phase_of(at.s + step_q)
            .or_else(|| self.phase_of(self.ahead(1).0));
        let Some(mut p) = near else {
            return false;
        };
        if let Some((seg, end)) = self.ramp_segment(p, eps, hz, t_last) {
            // The cursor moves to the segment's last tick (its exact time).
            self.seg = seg;
            self.at = end;
            return true;
        }
        let cap = self.run_left;
        let (mut n, linear) = if p != at.phase || at.v <= 0.0 || cap <= 1 {
            // The first tick of a phase (or from rest) is timed exactly on its own.
            (1, true)
        } else {
            self.segment_len(p, cap, eps, hz)
        };
        // The segment's end: within the phase.
        let (s1, rate1) = loop {
            let (s1, rate1) = self.ahead(n);
            let ds = s1 - at.s;
            let end = match p {
                Phase::Up => self.ends_q[0],
                Phase::Cruise => self.ends_q[1],
                Phase::Down => self.ends_q[2],
            };
            if s1 <= end {
                break (s1, rate1);
            }
            if n > 1 {
                let room = end.saturating_sub(at.s) as f32;
                n = ((n as f32 * room / ds as f32) as u32).max(1).min(n - 1);
                continue;
            }
            match self.phase_of(s1) {
                Some(next) if next != p => p = next,
                // Beyond the profile's end: timed on its own.
                _ => return false,
            }
        };
        let end = self.exact(p, s1, hz);
        let span = end.at.saturating_sub(at.at) as f32;
        let (d, longest) = if n == 1 {
            ([fixed(span), 0, 0], span)
        } else if linear {
            let d1 = span / n as f32;
            ([fixed(d1), 0, 0], d1)
        } else {
            // The slopes (timer ticks per tick) at both ends.
            let per = self.scale * hz;
            let m0 = at.rate * per / at.v;
            let m1 = rate1 * per / end.v.max(1e-9);
            let d = hermite(n, span, m0, m1);
            (d.map(fixed), m0.max(m1).max(d[0]))
        };
        if longest > (MAX_WAIT / 2) as f32 {
            // A wait may exceed a command's 24 bits: this tick goes on its own.
            return false;
        }
        self.seg = Segment::poly(n, d, at.at, t_last);
        self.at = Cursor { rate: rate1, ..end };
        true
    }

    /// Ticks in a ramp of constant acceleration (trapezoid), timed exactly
    /// ([`Ramp`]): a line's up to the ramp's end; a curve's as far as its path position
    /// stays within the error bound of a cubic in the tick count. `None` for anything
    /// else (or a ramp so long that its times leave 2^30 timer ticks).
    fn ramp_segment(&self, p: Phase, eps: f32, hz: f32, t_last: u64) -> Option<(Segment, Cursor)> {
        let [acc, jerk, _] = self.prof.derivative_bounds(p);
        if p == Phase::Cruise || !(acc > 0.0) || jerk != 0.0 {
            return None;
        }
        let at = self.at;
        let end = match p {
            Phase::Up => self.ends_q[0],
            _ => self.ends_q[2],
        };
        let (v0, v1) = self.prof.phase_speeds(p);
        let per_s = hz / acc; // R per mm/s, timer ticks
        if v0.max(v1) * per_s >= (1u32 << 30) as f32 {
            return None;
        }
        let k = 2.0 * hz * per_s; // W per mm, ticks^2
        let square = |v: f32| {
            let r = (v * per_s + 0.5) as u64;
            (r * r, r as u32)
        };
        // W grows along the path in the first ramp (if it speeds up), falls otherwise.
        let grows = p == Phase::Up && v1 >= v0;
        let (n, w, dw1, dw2, dw3, s1, rate1) = if let Some(q) = self.line_tick_q {
            // A line: whole ticks up to the ramp's end, W from whole ticks from its
            // anchor, so that a ramp to rest ends exactly at W = 0 (where time is most
            // sensitive to it).
            let n = (ticks_in(end.saturating_sub(at.s), q) as u32).min(self.run_left);
            let dw = (k * from_q(q)) as u64;
            let ticks = if p == Phase::Up {
                ticks_in(at.s, q)
            } else {
                u64::from(n)
            };
            let d = ticks.wrapping_mul(dw);
            let w = match p {
                Phase::Up if grows => square(v0).0 + d,
                Phase::Up => square(v0).0.saturating_sub(d),
                _ => square(v1).0 + d,
            };
            let s1 = at.s + q * u64::from(n);
            (
                n,
                w,
                if grows { dw } else { dw.wrapping_neg() },
                0,
                0,
                s1,
                1.0,
            )
        } else {
            // A curve: as many ticks as a cubic of the path position follows within
            // the bound (the time error is the position error over the speed).
            let to_end = from_q(end.saturating_sub(at.s)) / (at.rate * self.scale);
            let mut n = self
                .run_left
                .min(MAX_SEGMENT)
                .min(to_end.max(1.0) as u32)
                .max(1);
            let s4 = self.interp.run_bounds(n)[3] * self.scale;
            // Halving until the bound holds at the segment's slowest point (its start
            // when speeding up, its end when slowing down).
            loop {
                let nf = n as f32;
                let v2 = if grows {
                    at.v * at.v
                } else {
                    at.v * at.v - 2.0 * acc * nf * self.scale * 1.415
                };
                let room = 384.0 * eps * crate::fmath::sqrt(v2.max(0.0));
                if n == 1 || s4 * nf * nf * nf * nf <= room {
                    break;
                }
                n /= 2;
            }
            let (s1, rate1) = loop {
                let (s1, r) = self.ahead(n);
                if s1 <= end || n == 1 {
                    break (s1, r);
                }
                n = (n / 2).max(1);
            };
            if s1 > end {
                return None;
            }
            let ds = from_q(s1 - at.s) / self.scale;
            // W at the segment's last tick (exactly the anchor's at the end of a ramp to
            // rest, where the time is most sensitive to it).
            let d1 = match p {
                Phase::Up => from_q(s1),
                _ => from_q(end.saturating_sub(s1)),
            };
            let w_end = match p {
                Phase::Up if grows => square(v0).0 as f32 + k * d1,
                Phase::Up => square(v0).0 as f32 - k * d1,
                _ => square(v1).0 as f32 + k * d1,
            };
            let w_end = if d1 == 0.0 {
                match p {
                    Phase::Up => square(v0).0,
                    _ => square(v1).0,
                }
            } else {
                w_end.max(0.0) as u64
            };
            // W along the segment: the Hermite cubic of the path position (run units),
            // scaled to W, as forward differences; the start is set back from the end
            // by their exact sum.
            let kk = if grows {
                k * self.scale
            } else {
                -k * self.scale
            };
            let [e1, e2, e3] = hermite(n, ds, at.rate, rate1).map(|d| (kk * d) as i64);
            // The sums of 1, k and k(k-1)/2 over the ticks: n <= MAX_SEGMENT, so they
            // fit in 32 bits (a 64-bit division would link a kilobyte of library code).
            let pairs = n * (n - 1) / 2;
            let triples = pairs * n.saturating_sub(2) / 3;
            let sum = i64::from(n) * e1 + i64::from(pairs) * e2 + i64::from(triples) * e3;
            (
                n,
                (w_end as i64).wrapping_sub(sum).max(0) as u64,
                e1 as u64,
                e2 as u64,
                e3 as u64,
                s1,
                rate1,
            )
        };
        if n == 0 || (dw1 as i64).unsigned_abs() > 1 << 46 {
            // None, or a first or last step slower than half a command's wait: that
            // one goes on its own.
            return None;
        }
        let (anchor, r_ref, rising_t) = match p {
            Phase::Up => (self.anchors[0], square(v0).1, grows),
            _ => (self.anchors[2], square(v1).1, false),
        };
        // The tick's time: anchor + (R - R_ref) (rising) or anchor - (R - R_ref).
        let off = if rising_t {
            anchor.wrapping_sub(u64::from(r_ref))
        } else {
            anchor.wrapping_add(u64::from(r_ref))
        };
        let r = Ramp::root_near(w, (at.v * per_s) as u32);
        let dr = if r > 0 {
            (dw1 as i64 as f32 / (2 * r) as f32) as i32
        } else {
            0
        };
        let ramp = Ramp {
            w,
            dw1,
            dw2,
            dw3,
            rising_t,
            r0: off.wrapping_sub(at.at) as u32,
            r,
            dr,
            ddr: 0,
        };
        let seg = Segment {
            left: n,
            timing: Timing::Ramp(ramp),
            base: at.at,
            at: t_last.wrapping_sub(at.at) as u32,
        };
        Some((
            seg,
            Cursor {
                rate: rate1,
                ..self.exact(p, s1, hz)
            },
        ))
    }

    /// The longest segment (at most `cap` ticks, and where the time is not linear in
    /// the tick count at most [`MAX_SEGMENT`], a power-of-two fraction of it) whose
    /// timing polynomial stays within `eps` seconds of the ideal: h^4/384 times a bound
    /// of the tick time's fourth derivative, from the phase's acceleration, jerk and
    /// its rate, the speed (its lowest in the segment) and the path's derivatives.
    fn segment_len(&self, p: Phase, cap: u32, eps: f32, hz: f32) -> (u32, bool) {
        let at = self.at;
        let per_tick = at.rate * self.scale;
        // Ticks to the phase's end at the present rate, and a segment's longest span.
        let end = match p {
            Phase::Up => self.ends_q[0],
            Phase::Cruise => self.ends_q[1],
            Phase::Down => self.ends_q[2],
        };
        let to_end = from_q(end.saturating_sub(at.s)) / per_tick;
        let by_time = MAX_SEGMENT_TICKS * at.v / (per_tick * hz);
        let mut n = cap
            .min(to_end.max(1.0) as u32)
            .min(by_time.max(1.0) as u32)
            .max(1);
        let [acc, jerk, djerk] = self.prof.derivative_bounds(p);
        let [r1, r2, r3, r4] = self.interp.run_bounds(n);
        let sc = self.scale;
        let (s1, s2, s3, s4) = (r1 * sc, r2 * sc, r3 * sc, r4 * sc);
        if acc == 0.0 && s2 == 0.0 {
            // Time is linear in the tick count; [`MAX_LINEAR`] bounds the f32 rounding
            // of the interval before the next exact time.
            return (n.min(MAX_LINEAR), true);
        }
        n = n.min(MAX_SEGMENT);
        // |d^4 t / dk^4| at speed v (in a cruise only the path's curvature counts).
        let bound = |v: f32| {
            if acc == 0.0 {
                return s4 / v;
            }
            let x = 1.0 / v;
            let x2 = x * x;
            let x4 = x2 * x2;
            let t2 = acc * x2 * x;
            let t3 = jerk * x4 + 3.0 * acc * acc * x4 * x;
            let t4 = x4 * x * (djerk + x * (10.0 * acc * jerk + 15.0 * acc * acc * acc * x));
            let s1sq = s1 * s1;
            t4 * s1sq * s1sq + 6.0 * t3 * s1sq * s2 + t2 * (3.0 * s2 * s2 + 4.0 * s1 * s3) + x * s4
        };
        let limit = 384.0 * eps;
        // The largest power-of-two fraction of n with bound * n^4 <= limit: one bound,
        // then a factor 16 per halving.
        let fits = |b: f32, n: u32| {
            let nf = n as f32;
            let mut x = b * nf * nf * nf * nf;
            let mut n = n;
            while n > 1 && !(x <= limit) {
                x *= 1.0 / 16.0;
                n /= 2;
            }
            n
        };
        let v = at.v;
        n = fits(bound(v), n);
        if !self.prof.phase_rises(p) {
            // Slowing down: the segment's lowest speed is at its end.
            while n > 1 {
                let v2 = v * v - 2.0 * acc * n as f32 * s1;
                let m = if v2 > 0.0 {
                    fits(bound(crate::fmath::sqrt(v2)), n)
                } else {
                    n / 2
                };
                if m == n {
                    break;
                }
                n = m;
            }
        }
        (n, false)
    }
}

#[cfg(test)]
mod tests {
    //! Timing accuracy against the ideal profile, computed in f64 from the same block
    //! (length, speed limit, acceleration) with the profile's own formulas.
    use super::*;
    use crate::interpolation::Method;
    use crate::motion::{Feed, Move, Path};
    use crate::planner::{geometry, AxisConfig, Shape};
    use proptest::prelude::*;
    use std::vec::Vec;

    const HZ: f64 = 72_000_000.0;

    /// Every command, in order.
    struct VecSink(Vec<StepCmd>);

    impl CmdSink for VecSink {
        fn room(&self) -> usize {
            48
        }
        fn push_slice(&mut self, cmds: &[StepCmd]) -> usize {
            self.0.extend_from_slice(cmds);
            cmds.len()
        }
    }

    /// Step times (seconds) of `mv` prepared from rest at the origin, pure waits folded
    /// into the next step.
    fn step_times(cfg: PlannerConfig, mv: &Move) -> Vec<f64> {
        let mut planner = Planner::new(cfg, [0; 3]);
        planner.push(mv).unwrap();
        let mut prep = Prep::new(PrepConfig::default(), [0; 3]);
        let mut sink = VecSink(Vec::new());
        for _ in 0..10_000_000 {
            prep.fill(&mut planner, &mut sink, 48);
            if prep.is_idle(&planner) {
                break;
            }
        }
        let mut t = 0u64;
        let mut out = Vec::new();
        for c in &sink.0 {
            t += u64::from(c.wait());
            if c.tick().steps() != 0 {
                out.push(t as f64 / HZ);
            }
        }
        out
    }

    /// The ideal rest-to-rest profile in f64: time at path position `s`.
    struct Ideal {
        shape: Shape,
        a: f64,
        peak: f64,
        ramp_t: f64,
        ramp_d: f64,
        total: f64,
    }

    impl Ideal {
        fn new(shape: Shape, v_max: f64, a: f64, len: f64) -> Self {
            let ae = match shape {
                Shape::Trapezoid => a,
                Shape::Cosine => a * 2.0 / std::f64::consts::PI,
            };
            let peak = (ae * len).sqrt().min(v_max);
            let ramp_t = match shape {
                Shape::Trapezoid => peak / a,
                Shape::Cosine => std::f64::consts::PI * peak / (2.0 * a),
            };
            let ramp_d = 0.5 * peak * ramp_t;
            let total = 2.0 * ramp_t + (len - 2.0 * ramp_d).max(0.0) / peak;
            Ideal {
                shape,
                a,
                peak,
                ramp_t,
                ramp_d,
                total,
            }
        }

        /// Time into a ramp from rest at which it has covered `d`.
        fn ramp(&self, d: f64) -> f64 {
            match self.shape {
                Shape::Trapezoid => (2.0 * d / self.a).sqrt(),
                Shape::Cosine => {
                    let w = std::f64::consts::PI / self.ramp_t;
                    let s = |t: f64| 0.5 * self.peak * (t - (w * t).sin() / w);
                    let (mut lo, mut hi) = (0.0, self.ramp_t);
                    for _ in 0..100 {
                        let mid = 0.5 * (lo + hi);
                        if s(mid) < d {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    0.5 * (lo + hi)
                }
            }
        }

        /// Time at path position `s`, `left` before the end (both given, so that a
        /// position near the end keeps its precision: the time of the last steps of a
        /// ramp to rest is most sensitive to it).
        fn time(&self, s: f64, left: f64) -> f64 {
            if s <= self.ramp_d {
                self.ramp(s)
            } else if left > self.ramp_d {
                self.ramp_t + (s - self.ramp_d) / self.peak
            } else {
                self.total - self.ramp(left.max(0.0))
            }
        }
    }

    fn config(shape: Shape, steps_per_mm: f32, rate: f32, accel: f32) -> PlannerConfig {
        let axis = AxisConfig {
            steps_per_mm,
            max_rate: rate,
            accel,
        };
        PlannerConfig {
            axes: [axis, axis, axis],
            shape,
            ..PlannerConfig::default()
        }
    }

    /// Largest |step time - ideal time| along a line, seconds, and its duration.
    fn line_error(cfg: PlannerConfig, target: [i32; 3], feed: f32) -> (f64, f64) {
        let mv = Move {
            target,
            path: Path::Line,
            feed: Feed::MmPerMin(feed),
            line: 0,
        };
        let g = geometry::of_move(&cfg, [0; 3], &mv).unwrap();
        let v_max = (feed / 60.0).min(g.speed_limit);
        let ideal = Ideal::new(
            cfg.shape,
            f64::from(v_max),
            f64::from(g.accel),
            f64::from(g.length),
        );
        let times = step_times(cfg, &mv);
        let ticks = target.iter().map(|v| v.unsigned_abs()).max().unwrap();
        assert_eq!(times.len(), ticks as usize);
        let per = f64::from(g.length) / f64::from(ticks);
        let mut worst = 0.0f64;
        for (k, t) in times.iter().enumerate() {
            let done = (k + 1) as f64;
            worst = worst.max((t - ideal.time(done * per, (f64::from(ticks) - done) * per)).abs());
        }
        (worst, ideal.total)
    }

    #[test]
    fn a_trapezoid_line_is_timed_to_the_timer_tick() {
        let (err, _) = line_error(
            config(Shape::Trapezoid, 80.0, 3000.0, 500.0),
            [8000, 3000, 0],
            3000.0,
        );
        assert!(err < 0.3e-6, "{err}");
    }

    /// Largest |step time - ideal time| along an arc, seconds, and its duration. A
    /// tick's ideal position is the circle's point at its major coordinate (computed
    /// here in f64 from the tick's position and its piece's major axis, which a copy of
    /// the interpolator tells); extra steps (settle, tail) and ticks beyond the
    /// profile's end (length rounding) are not compared.
    fn arc_error(cfg: PlannerConfig, mv: &Move, center: [f64; 2], r: f64) -> (f64, f64) {
        let g = geometry::of_move(&cfg, [0; 3], mv).unwrap();
        let feed = match mv.feed {
            Feed::MmPerMin(f) => f / 60.0,
            Feed::Rapid => f32::INFINITY,
        };
        let v_max = feed.min(g.speed_limit);
        let times = step_times(cfg, mv);
        let spm = f64::from(cfg.axes[0].steps_per_mm);
        let mut runs = Vec::new();
        let mut it = Interpolator::new([0; 3], mv, cfg.method).unwrap();
        let mut p = [0i32; 3];
        let mut k = 0;
        let mut last_angle: Option<f64> = None;
        let mut s = 0.0f64;
        loop {
            let next = it.next();
            let major = match &it {
                Interpolator::Circle(c) => c.major(),
                _ => 0,
            };
            let mut one = [Tick(0)];
            if it.ticks_into(&mut one) == 0 {
                break;
            }
            one[0].apply(&mut p);
            let t = times[k];
            k += 1;
            if !matches!(next, Next::Run(_)) {
                continue;
            }
            // The circle's point at the tick's major coordinate, on its side.
            let rel = [f64::from(p[0]) - center[0], f64::from(p[1]) - center[1]];
            let n = 1 - major;
            let mut q = [0.0; 2];
            q[major] = rel[major].clamp(-r, r);
            q[n] = (r * r - q[major] * q[major]).max(0.0).sqrt() * rel[n].signum();
            let angle = q[1].atan2(q[0]);
            if let Some(a) = last_angle {
                let mut d = angle - a;
                if d > std::f64::consts::PI {
                    d -= std::f64::consts::TAU;
                } else if d < -std::f64::consts::PI {
                    d += std::f64::consts::TAU;
                }
                s += d.abs() * r / spm;
            } else {
                // The first tick: from the ideal point at the start's major coordinate.
                let start = [-center[0], -center[1]];
                let mut q0 = [0.0; 2];
                q0[major] = start[major].clamp(-r, r);
                q0[n] = (r * r - q0[major] * q0[major]).max(0.0).sqrt() * start[n].signum();
                let mut d = angle - q0[1].atan2(q0[0]);
                if d > std::f64::consts::PI {
                    d -= std::f64::consts::TAU;
                } else if d < -std::f64::consts::PI {
                    d += std::f64::consts::TAU;
                }
                s += d.abs() * r / spm;
            }
            last_angle = Some(angle);
            runs.push((s, t));
        }
        // The ideal over the planned length, or over the path's exact length (the
        // preparation rebuilds the profile to end at the arc's last step when its last
        // piece begins in a cruise or a trapezoid's first ramp): the run must follow one
        // of them all along.
        let planned = f64::from(g.length);
        let exact = runs.last().map_or(0.0, |r| r.0);
        let mut best = f64::INFINITY;
        for len in [planned, exact] {
            let ideal = Ideal::new(cfg.shape, f64::from(v_max), f64::from(g.accel), len);
            // Over the planned length the last step (a fraction of a step from its end,
            // by rounding) comes at the end itself: not compared.
            let runs = if len == planned {
                runs.get(..runs.len().saturating_sub(1)).unwrap_or(&[])
            } else {
                &runs[..]
            };
            let mut w = 0.0f64;
            // Positions along an arc are sums in f32 (to a thousandth of a step plus
            // 2e-7 of the distance): near a stop, where that is worth more than a
            // microsecond, the error is taken at the nearest point within it.
            for &(s, t) in runs.iter().filter(|r| r.0 <= len) {
                let tol = 1e-3 / spm + 2e-7 * s;
                let lo = ideal.time((s - tol).max(0.0), (len - s + tol).min(len));
                let hi = ideal.time((s + tol).min(len), (len - s - tol).max(0.0));
                let e = if t < lo {
                    lo - t
                } else if t > hi {
                    t - hi
                } else {
                    0.0
                };
                w = w.max(e);
            }
            best = best.min(w);
        }
        let ideal = Ideal::new(cfg.shape, f64::from(v_max), f64::from(g.accel), planned);
        assert_eq!(k, times.len());
        (best, ideal.total)
    }

    #[test]
    fn an_arc_is_timed_within_a_microsecond() {
        let cfg = config(Shape::Trapezoid, 80.0, 3000.0, 500.0);
        let mv = Move {
            target: [0; 3],
            path: Path::Arc {
                center: [1600, 0],
                ccw: false,
                turns: 0,
            },
            feed: Feed::MmPerMin(3000.0),
            line: 0,
        };
        let (err, total) = arc_error(cfg, &mv, [1600.0, 0.0], 1600.0);
        assert!(err <= 1e-6 + 2e-7 * total, "{} us", err * 1e6);
    }

    /// Every step event of `moves` prepared from rest at the origin: (timer tick,
    /// position after it).
    fn events(cfg: PlannerConfig, moves: &[Move]) -> Vec<(u64, StepPos)> {
        let mut planner = Planner::new(cfg, [0; 3]);
        for mv in moves {
            planner.push(mv).unwrap();
        }
        let mut prep = Prep::new(PrepConfig::default(), [0; 3]);
        let mut sink = VecSink(Vec::new());
        for _ in 0..10_000_000 {
            prep.fill(&mut planner, &mut sink, 48);
            if prep.is_idle(&planner) {
                break;
            }
        }
        let (mut t, mut pos) = (0u64, [0i32; 3]);
        let mut out = Vec::new();
        for c in &sink.0 {
            t += u64::from(c.wait());
            let d = c.tick().deltas();
            if c.tick().steps() != 0 {
                for (p, d) in pos.iter_mut().zip(d) {
                    *p += i32::from(d);
                }
                out.push((t, pos));
            }
        }
        out
    }

    /// The shortest interval between two step events the drivers and the step
    /// pipeline take, timer ticks (1 / MAX_STEP_RATE, less a tick of rounding).
    fn shortest_allowed() -> u64 {
        (HZ / f64::from(MAX_STEP_RATE)) as u64 - 1
    }

    /// The smallest case the emulator found (emu/random-regressions/seed-143959954.nc):
    /// `$212=0`, an R arc at 1500 mm/min whose classic trace stops where X reaches the
    /// target's coordinate, 8 steps short in Y; the straight tail to the target was
    /// timed as catch-up steps at halving intervals down to 5.5 us, and the board's
    /// driver lost a step.
    #[test]
    fn a_classic_arc_with_a_long_tail_keeps_its_steps_apart() {
        let mut cfg = config(Shape::Trapezoid, 80.0, 3000.0, 500.0);
        cfg.method = Method::Classic;
        // G3 X0.0848 Y0.8765 R3.2101 from the origin (the centre from the R form),
        // then G1 X-4.8475 Y6.6434, in steps at 80 steps/mm.
        let (ex, ey, r) = (0.0848f64 * 80.0, 0.8765f64 * 80.0, 3.2101f64 * 80.0);
        let (mx, my) = (ex / 2.0, ey / 2.0);
        let half = ex.hypot(ey) / 2.0;
        let h = (r * r - half * half).sqrt();
        let (ux, uy) = (-ey / (2.0 * half), ex / (2.0 * half));
        let (cx, cy) = (mx + h * ux, my + h * uy);
        let q = |v: f64| (v * 256.0).round() as i32;
        let arc = Move {
            target: [ex.round() as i32, ey.round() as i32, 0],
            path: Path::ArcFine {
                from: [0, 0],
                center: [q(cx), q(cy)],
                ccw: true,
                turns: 0,
            },
            feed: Feed::MmPerMin(1500.0),
            line: 0,
        };
        let line = Move {
            target: [
                (-4.8475f64 * 80.0).round() as i32,
                (6.6434f64 * 80.0).round() as i32,
                0,
            ],
            path: Path::Line,
            feed: Feed::MmPerMin(1500.0),
            line: 1,
        };
        let ev = events(cfg, &[arc, line]);
        let gap = ev.windows(2).map(|w| w[1].0 - w[0].0).min().unwrap();
        assert!(gap >= shortest_allowed(), "{} us", gap as f64 / HZ * 1e6);
        assert_eq!(ev.last().unwrap().1, line.target);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Arcs (off-grid centres, either way, either tracing) followed by a line: no
        /// two step events closer than the step pipeline's cap, and the exact target.
        #[test]
        fn arc_step_events_keep_the_cap_and_end_on_the_target(
            cx in -800.0f64..800.0, cy in -800.0f64..800.0, end in 0.0f64..std::f64::consts::TAU,
            feed in 60.0f32..6000.0, accel in 50.0f32..3000.0, ccw in any::<bool>(),
            classic in any::<bool>(), cosine in any::<bool>(), lx in -400i32..400, ly in -400i32..400) {
            let r = cx.hypot(cy);
            prop_assume!(r > 4.0 && (lx != 0 || ly != 0));
            let shape = if cosine { Shape::Cosine } else { Shape::Trapezoid };
            let mut cfg = config(shape, 80.0, 6000.0, accel);
            cfg.method = if classic { Method::Classic } else { Method::Dda };
            let q = |v: f64| (v * 256.0).round() as i32;
            let target = [(cx + r * end.cos()).round() as i32, (cy + r * end.sin()).round() as i32, 0];
            let arc = Move {
                target,
                path: Path::ArcFine { from: [0, 0], center: [q(cx), q(cy)], ccw, turns: 0 },
                feed: Feed::MmPerMin(feed),
                line: 0,
            };
            let line = Move {
                target: [target[0] + lx, target[1] + ly, 0],
                path: Path::Line,
                feed: Feed::MmPerMin(feed),
                line: 1,
            };
            let ev = events(cfg, &[arc, line]);
            let gap = ev.windows(2).map(|w| w[1].0 - w[0].0).min().unwrap_or(u64::MAX);
            prop_assert!(gap >= shortest_allowed(), "{} us apart", gap as f64 / HZ * 1e6);
            prop_assert_eq!(ev.last().map(|e| e.1).unwrap_or([0; 3]), line.target);
        }

        #[test]
        fn arc_steps_are_within_a_microsecond_of_the_ideal_profile(
            cx in -3000.0f64..3000.0, cy in -3000.0f64..3000.0, end in 0.0f64..std::f64::consts::TAU,
            feed in 60.0f32..6000.0, accel in 50.0f32..3000.0, ccw in any::<bool>(), cosine in any::<bool>()) {
            let r = cx.hypot(cy);
            prop_assume!(r > 20.0);
            let shape = if cosine { Shape::Cosine } else { Shape::Trapezoid };
            let cfg = config(shape, 80.0, 6000.0, accel);
            let q = |v: f64| (v * 256.0).round() as i32;
            let target = [(cx + r * end.cos()).round() as i32, (cy + r * end.sin()).round() as i32, 0];
            let mv = Move {
                target,
                path: Path::ArcFine { from: [0, 0], center: [q(cx), q(cy)], ccw, turns: 0 },
                feed: Feed::MmPerMin(feed),
                line: 0,
            };
            let c = [f64::from(q(cx)) / 256.0, f64::from(q(cy)) / 256.0];
            let (err, total) = arc_error(cfg, &mv, c, c[0].hypot(c[1]));
            prop_assert!(err <= 1e-6 + 2e-7 * total, "error {} us over {} s", err * 1e6, total);
        }

        #[test]
        fn line_steps_are_within_a_microsecond_of_the_ideal_profile(
            dx in -6000i32..6000, dy in -6000i32..6000, feed in 30.0f32..6000.0,
            accel in 20.0f32..3000.0, spm in prop::sample::select(std::vec![40.0f32, 80.0, 320.0, 1280.0]),
            cosine in any::<bool>()) {
            prop_assume!(dx != 0 || dy != 0);
            let shape = if cosine { Shape::Cosine } else { Shape::Trapezoid };
            let (err, total) = line_error(config(shape, spm, 6000.0, accel), [dx, dy, 0], feed);
            prop_assert!(err <= 1e-6 + 2e-7 * total, "error {} us over {} s", err * 1e6, total);
        }
    }
}
