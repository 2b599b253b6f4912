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
//! profile's distance law on short windows (linear inside a 0.5 ms window) and rounded
//! to whole timer ticks against an absolute clock, so rounding never accumulates.
//!
//! The profile is rebuilt from the present state whenever the planner's generation
//! changes (a new block, an override), and for feed hold (brake to rest, possibly over
//! several blocks) and resume. Hold keeps the next tick pending, so no step is lost.

use super::{CmdSink, StepCmd, MAX_WAIT};
use crate::interp::{Interp, Interpolate, Tick};
use crate::motion::{StepPos, AXES, X, Y};
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
            window_s: 0.0005,
        }
    }
}

#[derive(Clone, Debug)]
struct Active {
    block: Block,
    interp: Interp,
    /// Constant tick length (lines), mm.
    line_ds: Option<f64>,
    /// Path length covered by queued ticks, mm from the block start.
    s: f64,
    prof: Profile,
    /// Block distance and absolute timer tick where the profile starts.
    prof_s0: f64,
    prof_t0: u64,
    /// Inversion window (seconds and mm relative to the profile start).
    win: [f64; 4],
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
                let rest = (f64::from(a.block.length) - a.s).max(0.0) as f32;
                planner.set_head_cap(libm::sqrtf(self.v_last * self.v_last + 2.0 * ae * rest));
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
    pub fn fill(&mut self, planner: &mut Planner, sink: &mut impl CmdSink) {
        let cfg = *planner.config();
        while sink.has_room() {
            if self.hold == HoldState::Held {
                return;
            }
            if self.active.is_none() && !self.start_next(planner, &cfg) {
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
                self.v_last = speed_at_distance(&a.prof, a.s - a.prof_s0) as f32;
                self.active = None;
                continue;
            };
            let ds = match (a.line_ds, &a.interp) {
                (Some(ds), _) => ds,
                (None, Interp::Conic(c)) => c.last_tick_len(
                    f64::from(cfg.axes[X].steps_per_mm),
                    f64::from(cfg.axes[Y].steps_per_mm),
                ),
                (None, _) => curve_ds(&cfg, a.interp.direction().unwrap_or([1.0, 0.0])),
            };
            let s_new = a.s + ds;
            let hz = f64::from(self.cfg.timer_hz);
            let Some((t_rel, v)) = invert(
                &a.prof,
                &mut a.win,
                s_new - a.prof_s0,
                self.cfg.window_s,
                self.hold,
                self.v_last,
            ) else {
                // Braked to rest before this tick: keep it for the resume.
                a.pending = Some(tick);
                self.hold = HoldState::Held;
                self.v_last = 0.0;
                return;
            };
            let abs = a.prof_t0 + (t_rel * hz + 0.5) as u64;
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
            a.s = s_new;
            tick.apply(&mut self.pos);
            self.v_last = v;
        }
    }

    fn start_next(&mut self, planner: &mut Planner, cfg: &PlannerConfig) -> bool {
        loop {
            let Some(block) = planner.pop() else {
                planner.note_stopped();
                if self.hold == HoldState::Holding {
                    self.hold = HoldState::Held;
                }
                return false;
            };
            match Interp::new(self.pos, &block.mv, cfg.method) {
                Ok(interp) => {
                    let line_ds = match interp.direction() {
                        Some(_) => None,
                        None => Some(line_tick_len(cfg, self.pos, block.mv.target)),
                    };
                    let ae = planner.plan_accel(&block);
                    self.active = Some(Active {
                        block,
                        interp,
                        line_ds,
                        s: 0.0,
                        prof: Profile::new(cfg.shape, 0.0, 0.0, 0.0, 1.0, 0.0),
                        prof_s0: 0.0,
                        prof_t0: self.t_last,
                        win: [0.0; 4],
                        pending: None,
                    });
                    let v = self.v_last;
                    planner.set_head_cap(libm::sqrtf(v * v + 2.0 * ae * block.length));
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
        let rest = (f64::from(a.block.length) - a.s).max(0.0) as f32;
        let v0 = if self.hold == HoldState::Running {
            self.v_last.max(cfg.start_speed)
        } else {
            self.v_last
        };
        a.prof = Profile::new(cfg.shape, v0, v_max, v_exit, a.block.accel, rest);
        a.prof_s0 = a.s;
        a.prof_t0 = self.t_last;
        a.win = [0.0; 4];
    }
}

/// Tick length of a line, mm: path length over the number of ticks.
fn line_tick_len(cfg: &PlannerConfig, from: StepPos, to: StepPos) -> f64 {
    let mut len2 = 0.0f64;
    let mut major = 0i64;
    let mut sum = 0i64;
    for i in 0..AXES {
        let d = i64::from(to[i]) - i64::from(from[i]);
        let mm = d as f64 / f64::from(cfg.axes[i].steps_per_mm.max(1e-6));
        len2 += mm * mm;
        major = major.max(d.abs());
        sum += d.abs();
    }
    let ticks = match cfg.method {
        crate::interp::Method::Dda => major,
        crate::interp::Method::Classic => sum,
    };
    if ticks == 0 {
        0.0
    } else {
        libm::sqrt(len2) / ticks as f64
    }
}

/// Ideal path length per tick along a curve with feed direction `t` (steps), mm.
fn curve_ds(cfg: &PlannerConfig, t: [f32; 2]) -> f64 {
    let (tx, ty) = (t[0].abs(), t[1].abs());
    let mx = tx / cfg.axes[X].steps_per_mm.max(1e-6);
    let my = ty / cfg.axes[Y].steps_per_mm.max(1e-6);
    let mm = libm::sqrtf(mx * mx + my * my);
    let per = match cfg.method {
        crate::interp::Method::Dda => tx.max(ty),
        crate::interp::Method::Classic => tx + ty,
    };
    if per > 0.0 {
        f64::from(mm / per)
    } else {
        0.0
    }
}

/// Speed of the profile where it has covered `d`.
fn speed_at_distance(p: &Profile, d: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, p.duration());
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if p.at(mid).0 < d {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    p.at(hi).1
}

/// Time (s, from the profile start) and speed at which the profile covers `d` mm.
/// `None` when a hold brings the profile to rest before `d`.
fn invert(
    p: &Profile,
    win: &mut [f64; 4],
    d: f64,
    window: f32,
    hold: HoldState,
    v_last: f32,
) -> Option<(f64, f32)> {
    let dur = p.duration();
    let total = p.distance();
    if d > total {
        let v_end = p.exit_speed();
        if hold != HoldState::Running && v_end < 1e-3 {
            return None;
        }
        // Past the planned distance (rounding of curve lengths, a fraction of a step):
        // continue at the exit speed or, when that is zero, at the last tick's speed.
        let v = v_end.max(f64::from(v_last)).max(1e-3);
        let t = (d - total) / v;
        return Some((dur + t, v_end as f32));
    }
    let step = f64::from(window);
    while d > win[3] && win[2] < dur {
        win[0] = win[2];
        win[1] = win[3];
        win[2] = (win[0] + step).min(dur);
        win[3] = p.at(win[2]).0;
    }
    let (t0, s0, t1, s1) = (win[0], win[1], win[2], win[3]);
    let t = if s1 > s0 {
        t0 + (d - s0) / (s1 - s0) * (t1 - t0)
    } else {
        t1
    };
    let v = if t1 > t0 {
        ((s1 - s0) / (t1 - t0)) as f32
    } else {
        p.at(t).1 as f32
    };
    Some((t, v))
}
