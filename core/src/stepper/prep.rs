//! Segment preparation: pulls ticks from the interpolator of the block in execution
//! and gives each one its time from the block's velocity profile, producing
//! [`StepCmd`]s for the interrupt. Runs in a task below the step timer; floating
//! point is fine here, never in [`super::exec`].
//!
//! Timing: every tick advances the ideal path by a known length (constant for lines;
//! for circles and ellipses the arc between the parameter angles of the two points,
//! which sums exactly to the planned length; for y = f(x) 1/max|t_i| (DDA) or
//! 1/sum|t_i| (classic) of the unit tangent t in steps per mm), so the path speed is
//! constant along curves and a diagonal step takes
//! sqrt(2) times as long as an axial one. The tick's time is found by inverting the
//! profile's distance law on short windows (linear inside a 2 ms window) against an
//! absolute timer clock, so rounding never accumulates. Floating point runs once per
//! window; per tick, lines and circles take only integer adds and one multiply.
//!
//! The profile is rebuilt from the present state whenever the planner's generation
//! changes (a new block, an override), and for feed hold (brake to rest, possibly over
//! several blocks) and resume. Hold keeps the next tick pending, so no step is lost.

use super::{CmdSink, StepCmd, MAX_WAIT};
use crate::interpolation::{Interpolate, Interpolator, Tick};
use crate::motion::{StepPos, X, Y};
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
    /// Length of the profile-inversion window, seconds.
    pub window_s: f32,
}

impl Default for PrepConfig {
    fn default() -> Self {
        PrepConfig {
            timer_hz: 72_000_000,
            window_s: 0.002,
        }
    }
}

/// Distance unit of the per-tick path: 2^-32 mm, fine enough that rounding each
/// tick's length adds up to far less than a step over any block.
const Q: f32 = 4_294_967_296.0;

/// How each tick's length is found.
#[derive(Clone, Copy, Debug)]
enum TickLen {
    /// Constant (lines), in Q units.
    Const(u64),
    /// Circle: |cross(prev, next)| * m / dot(prev, next), with m = R in Q units.
    Circle(f32),
    /// Anything else: from the curve's tangent (floating point).
    Curve,
}

/// One inversion window of the profile, in integers: a tick at distance `s` (Q units
/// from the block start) happens at t0 + (s - s0) * k >> 32 timer ticks.
#[derive(Clone, Copy, Debug, Default)]
struct Window {
    /// Window end time, timer ticks from the profile start.
    t1: u64,
    s0: u64,
    s1: u64,
    t0_abs: u64,
    t1_abs: u64,
    /// Timer ticks per mm (= per Q unit with 32 fractional bits).
    k: u64,
    /// Mean speed in the window, mm/s.
    v: f32,
}

#[derive(Clone, Debug)]
struct Active {
    block: Block,
    interp: Interpolator,
    len: TickLen,
    /// Path length covered by queued ticks, Q units from the block start.
    s: u64,
    /// The length the ticks add up to (Q units).
    len_q: u64,
    /// Ticks left along a line: the last one lands exactly on `len_q`.
    ticks_left: Option<u64>,
    prof: Profile,
    /// Block distance (Q units) and absolute timer tick where the profile starts.
    prof_s0: u64,
    prof_t0: u64,
    /// The profile is exhausted (later ticks run at its exit speed).
    prof_done: bool,
    win: Window,
    pending: Option<Tick>,
}

/// The segment-preparation state.
#[derive(Clone, Debug)]
pub struct Prep {
    cfg: PrepConfig,
    active: Option<Active>,
    /// Absolute timer tick of the last queued step.
    t_last: u64,
    /// Path speed at that step, mm/s.
    v_last: f32,
    generation: u32,
    hold: HoldState,
    /// Position after the last queued tick.
    pos: StepPos,
    /// Blocks whose interpolation was rejected (skipped without moving).
    skipped: u32,
    /// Wait before the last queued step, timer ticks.
    last_wait: u64,
}

impl Prep {
    pub fn new(cfg: PrepConfig, position: StepPos) -> Self {
        Prep {
            cfg,
            active: None,
            t_last: 0,
            v_last: 0.0,
            generation: 0,
            hold: HoldState::Running,
            pos: position,
            skipped: 0,
            last_wait: 1,
        }
    }

    pub fn hold_state(&self) -> HoldState {
        self.hold
    }
    /// Nothing in execution and nothing left to prepare.
    pub fn is_idle(&self, planner: &Planner) -> bool {
        self.active.is_none() && planner.is_empty()
    }
    /// Position after the last prepared step.
    pub fn position(&self) -> StepPos {
        self.pos
    }
    /// Path speed at the last prepared step, mm/s.
    pub fn speed(&self) -> f32 {
        self.v_last
    }
    pub fn skipped(&self) -> u32 {
        self.skipped
    }
    /// Source line of the block in execution.
    pub fn line(&self) -> Option<u32> {
        self.active.as_ref().map(|a| a.block.mv.line)
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
                let rest = a.len_q.saturating_sub(a.s) as f32 / Q;
                planner.set_head_cap(crate::fmath::sqrt(
                    self.v_last * self.v_last + 2.0 * ae * rest,
                ));
            }
            self.generation = planner.generation().wrapping_sub(1);
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

    /// Prepares commands until `sink` is full, the path ends, or a hold comes to rest.
    /// `dyn`: one copy compiled in the core (size-optimised), not one per caller.
    pub fn fill(&mut self, planner: &mut Planner, sink: &mut dyn CmdSink) {
        while sink.has_room() {
            if self.hold == HoldState::Held {
                return;
            }
            if self.active.is_none() && !self.start_next(planner) {
                return;
            }
            if planner.generation() != self.generation {
                self.reprofile(planner);
            }
            let Some(a) = self.active.as_mut() else {
                return;
            };
            let Some(tick) = a.pending.take().or_else(|| a.interp.next_tick()) else {
                // Block done: carry the speed into the next one.
                self.v_last = if a.prof_done {
                    a.prof.exit_speed()
                } else {
                    a.win.v
                };
                self.active = None;
                continue;
            };
            let ds = match a.len {
                TickLen::Const(q) => q,
                len => curve_tick_len(len, &a.interp, planner.config()),
            };
            let mut s_new = a.s + ds;
            if let Some(n) = a.ticks_left.as_mut() {
                if *n == 1 {
                    s_new = a.len_q;
                }
                *n = n.saturating_sub(1);
            }
            // Integer fast path: the tick falls in the present (or a later) window.
            while s_new > a.win.s1 && !a.prof_done {
                advance_window(a, &self.cfg);
            }
            let (abs, v) = if s_new <= a.win.s1 {
                // off * k stays below 2^32 times the window's length in timer ticks.
                let off = s_new.saturating_sub(a.win.s0);
                (a.win.t0_abs + (off.wrapping_mul(a.win.k) >> 32), a.win.v)
            } else {
                // Past the profile's end: a hold stops here; otherwise (a catch-up step
                // of a fine line, curve length rounding) go on at the last step's rate.
                let v_end = a.prof.exit_speed();
                if self.hold != HoldState::Running && v_end < 1e-3 {
                    a.pending = Some(tick);
                    self.hold = HoldState::Held;
                    self.v_last = 0.0;
                    return;
                }
                // Overshoot of less than half this tick (length rounding): the profile's
                // end time.
                if (s_new - a.win.s1) * 2 <= ds {
                    (a.win.t1_abs, self.v_last)
                } else {
                    (self.t_last.max(a.win.t1_abs) + self.last_wait, self.v_last)
                }
            };
            let mut wait = abs.saturating_sub(self.t_last).max(1);
            // Long pauses: pure waits first.
            while wait > u64::from(MAX_WAIT) {
                if !sink.has_room() {
                    a.pending = Some(tick);
                    return;
                }
                sink.push(StepCmd::new(Tick(0), MAX_WAIT));
                self.t_last += u64::from(MAX_WAIT);
                wait -= u64::from(MAX_WAIT);
            }
            if !sink.has_room() {
                a.pending = Some(tick);
                return;
            }
            sink.push(StepCmd::new(tick, wait as u32));
            self.t_last += wait;
            self.last_wait = wait;
            a.s = s_new;
            tick.apply(&mut self.pos);
            self.v_last = v;
        }
    }

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
            match Interpolator::new(self.pos, &block.mv, cfg.method) {
                Ok(interp) => {
                    let (len_q, ticks_left, len) = match &interp {
                        Interpolator::Line(l) => {
                            let line_len = line_length(cfg, self.pos, block.mv.target);
                            let per = to_q(line_len / l.ticks().max(1) as f32);
                            (to_q(line_len), Some(l.ticks()), TickLen::Const(per))
                        }
                        Interpolator::Conic(c) => {
                            let len = match c.circle_radius() {
                                Some(r) if cfg.axes[X].steps_per_mm == cfg.axes[Y].steps_per_mm => {
                                    let sp = cfg.axes[X].steps_per_mm.max(1e-6);
                                    TickLen::Circle(Q * r / sp)
                                }
                                _ => TickLen::Curve,
                            };
                            (to_q(block.length), None, len)
                        }
                        Interpolator::Sine(_) => (to_q(block.length), None, TickLen::Curve),
                    };
                    let ae = planner.plan_accel(&block);
                    self.active = Some(Active {
                        block,
                        interp,
                        len,
                        s: 0,
                        len_q,
                        ticks_left,
                        prof: Profile::rest(cfg.shape),
                        prof_s0: 0,
                        prof_t0: self.t_last,
                        prof_done: false,
                        win: Window::default(),
                        pending: None,
                    });
                    let v = self.v_last;
                    planner.set_head_cap(crate::fmath::sqrt(v * v + 2.0 * ae * block.length));
                    self.generation = planner.generation().wrapping_sub(1);
                    return true;
                }
                Err(_) => self.skipped = self.skipped.wrapping_add(1),
            }
        }
    }

    fn reprofile(&mut self, planner: &Planner) {
        self.generation = planner.generation();
        let cfg = planner.config();
        let Some(a) = self.active.as_mut() else {
            return;
        };
        let (v_max, v_exit) = if self.hold == HoldState::Running {
            (planner.max_speed(&a.block), planner.exit_speed())
        } else {
            (0.0, 0.0)
        };
        let rest = a.len_q.saturating_sub(a.s) as f32 / Q;
        let v0 = if self.hold == HoldState::Running {
            self.v_last.max(cfg.start_speed)
        } else {
            self.v_last
        };
        a.prof = Profile::new(cfg.shape, v0, v_max, v_exit, a.block.accel, rest);
        a.prof_s0 = a.s;
        a.prof_t0 = self.t_last;
        a.prof_done = false;
        a.win = Window {
            s0: a.s,
            s1: a.s,
            t0_abs: self.t_last,
            t1_abs: self.t_last,
            ..Window::default()
        };
    }
}

fn to_q(mm: f32) -> u64 {
    (mm * Q + 0.5) as u64
}

/// Moves the window on by the configured length (floating point, once per window).
///
/// Kept out of line for speed: inlined into the tick loop it makes the loop keep more
/// values live, and segment preparation costs 1,130 instead of 934 instructions per
/// step event (bench/isr-cost/run, "segment preparation").
#[inline(never)]
fn advance_window(a: &mut Active, cfg: &PrepConfig) {
    // Time is kept in whole timer ticks (exact, no drift); only the profile is
    // evaluated in f32 seconds, whose rounding moves a window edge by far less than a step.
    let hz = cfg.timer_hz as f32;
    let dur = (a.prof.duration() * hz + 0.5) as u64;
    let t0 = a.win.t1;
    let t1 = (t0 + (cfg.window_s * hz + 0.5) as u64).min(dur);
    let t = t1 as f32 / hz;
    // The first half from the start, the second half back from the end: either way
    // the small distance near a slow end of the profile stays exact in f32.
    let s1 = if 2 * t1 <= dur {
        a.prof_s0 + to_q(a.prof.at(t).0)
    } else {
        (a.prof_s0 + to_q(a.prof.distance())).saturating_sub(to_q(a.prof.left(t)))
    };
    let t1_abs = a.prof_t0 + t1;
    let (s0, t0_abs) = (a.win.s1, a.win.t1_abs);
    let ds = s1.saturating_sub(s0);
    // f32 rather than a u64 division (not in the chip's instruction set).
    let k = if ds > 0 {
        ((t1_abs - t0_abs) as f32 * Q / ds as f32) as u64
    } else {
        0
    };
    let v = if t1 > t0 {
        (ds as f32 / Q) / ((t1 - t0) as f32 / hz)
    } else {
        a.win.v
    };
    a.win = Window {
        t1,
        s0,
        s1: s1.max(s0),
        t0_abs,
        t1_abs,
        k,
        v,
    };
    if t1 >= dur {
        a.prof_done = true;
    }
}

/// Length of the last tick along a curve, Q units (lines take the constant branch in
/// the loop).
fn curve_tick_len(len: TickLen, interp: &Interpolator, cfg: &PlannerConfig) -> u64 {
    match (len, interp) {
        (TickLen::Const(q), _) => q,
        (TickLen::Circle(m), Interpolator::Conic(c)) if !c.in_tail() => {
            // R * angle with angle = atan(cross / dot) ~ cross / dot: the angles
            // telescope, so a whole arc adds up to its length (to < 1e-9).
            // f32, not a u64 division (not in the chip's instruction set).
            // The cross product of neighbours is below 2^31 (see Conic::last_tick_len):
            // the same f32 through u32.
            let dot = c.last_dot().unsigned_abs().max(1) as f32;
            (c.last_cross().unsigned_abs() as u32 as f32 * m / dot) as u64
        }
        (_, Interpolator::Conic(c)) => {
            to_q(c.last_tick_len(cfg.axes[X].steps_per_mm, cfg.axes[Y].steps_per_mm))
        }
        (_, interp) => {
            // Only a sine gets here (conics are above): the conic's tangent is not
            // compiled in.
            let dir = match interp {
                Interpolator::Sine(c) => c.direction(),
                _ => [1.0, 0.0],
            };
            to_q(curve_ds(cfg, dir))
        }
    }
}

/// Length of a line, mm (travels below 2^31: the planner keeps both ends within
/// motion::POS_LIMIT, so i32 differences give the same f32 as i64 ones).
fn line_length(cfg: &PlannerConfig, from: StepPos, to: StepPos) -> f32 {
    let mut len2 = 0.0f32;
    for ((&t, &f), ax) in to.iter().zip(from.iter()).zip(cfg.axes.iter()) {
        let mm = t.wrapping_sub(f) as f32 / ax.steps_per_mm.max(1e-6);
        len2 += mm * mm;
    }
    crate::fmath::sqrt(len2)
}

/// Ideal path length per tick along a curve with feed direction `t` (steps), mm.
fn curve_ds(cfg: &PlannerConfig, t: [f32; 2]) -> f32 {
    let (tx, ty) = (t[0].abs(), t[1].abs());
    let mx = tx / cfg.axes[X].steps_per_mm.max(1e-6);
    let my = ty / cfg.axes[Y].steps_per_mm.max(1e-6);
    let mm = crate::fmath::sqrt(mx * mx + my * my);
    let per = match cfg.method {
        crate::interpolation::Method::Dda => tx.max(ty),
        crate::interpolation::Method::Classic => tx + ty,
    };
    if per > 0.0 {
        mm / per
    } else {
        0.0
    }
}
