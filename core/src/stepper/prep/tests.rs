//! Timing accuracy against the ideal profile, computed in f64 from the same block
//! (length, speed limit, acceleration) with the profile's own formulas.
use super::*;
use crate::interpolation::Method;
use crate::motion::{Feed, Move, Path};
use crate::planner::{geometry, AxisConfig, Shape};
use crate::stepper::MAX_STEP_RATE;
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
                crate::planner::profile::reference_ramp_time(0.0, self.peak, self.ramp_t, d)
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
        let mut one = [StepEvent(0)];
        if it.events_into(&mut one) == 0 {
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

/// Every step event of `moves` prepared from rest at the origin: (timer count,
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
/// pipeline take, timer counts (1 / MAX_STEP_RATE, less a tick of rounding).
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
