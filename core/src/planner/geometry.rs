//! What the planner needs to know about one move's shape, in millimetres: its length,
//! the tangent where it starts and ends (for junctions), the path acceleration and
//! speed that every axis can follow along it (Grbl's per-axis semantics: a path
//! direction u limits acceleration to min_i a_i / |u_i| and speed to min_i v_i / |u_i|),
//! and for curves the centripetal limit v^2 <= a * r_min; and the speed at which its
//! step events come no faster than the step side sustains (`event_cap`: the step
//! pipeline's cap, lower for long step pulses and for curves timed event by event).
//!
//! Lengths of curves are integrated numerically (Simpson); floating point is fine
//! here because this runs once per move in the planning task.

use super::PlannerConfig;
use crate::interpolation::Method;
use crate::motion::{Move, Path, StepPos, AXES, X, Y, Z};
use crate::stepper::MAX_SINGLE_EVENT_RATE;
use core::f32::consts::{PI, SQRT_2, TAU};

/// The planner's view of one move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Path length in mm.
    pub length: f32,
    /// Unit tangent at the start and at the end (mm space).
    pub unit_start: [f32; AXES],
    pub unit_end: [f32; AXES],
    /// Largest path acceleration every axis can follow along the whole move, mm/s^2.
    pub accel: f32,
    /// Largest path speed every axis can follow (axis max rates, centripetal) and the
    /// step side can time (`event_cap`), mm/s.
    pub speed_limit: f32,
}

/// Why a move has no usable geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryError {
    /// The move goes nowhere (or its curve has no length).
    Empty,
    /// Parameters that make no sense (zero radius, Z change on a planar curve...).
    Invalid,
}

/// Per-axis limits along direction `u` (unit, mm space): (accel, speed).
pub(super) fn axis_limits(cfg: &PlannerConfig, u: [f32; AXES]) -> (f32, f32) {
    let mut acc = f32::INFINITY;
    let mut spd = f32::INFINITY;
    for (ax, &c) in cfg.axes.iter().zip(u.iter()) {
        let c = c.abs();
        if c > 1e-9 {
            acc = acc.min(ax.accel / c);
            spd = spd.min(ax.max_rate / 60.0 / c);
        }
    }
    (acc, spd)
}

/// The length of `v` and `v` scaled to unit length (zero when the length is not
/// positive): one root for both, which every caller needs.
pub(super) fn length_and_unit(v: [f32; AXES]) -> (f32, [f32; AXES]) {
    let n = crate::fmath::sqrt(v.iter().map(|c| c * c).sum());
    let unit = if n > 0.0 {
        [v[0] / n, v[1] / n, v[2] / n]
    } else {
        [0.0; AXES]
    };
    (n, unit)
}

fn sp(cfg: &PlannerConfig, axis: usize) -> f32 {
    cfg.axes[axis].steps_per_mm.max(1e-6)
}

/// Geometry of `mv` starting at `start`.
pub fn of_move(cfg: &PlannerConfig, start: StepPos, mv: &Move) -> Result<Geometry, GeometryError> {
    let mut g = shape_of(cfg, start, mv)?;
    g.speed_limit = g
        .speed_limit
        .min(event_cap(cfg, mv) / events_per_mm(cfg, start, mv, g.length));
    Ok(g)
}

/// The step-event rate `mv` may ask for: [`MAX_SINGLE_EVENT_RATE`] when the preparation
/// times its step events one by one (an ellipse, a sine, a circle traced point by point:
/// each event's length is known only once it is made, `interpolation::Next::StepEvent`),
/// which costs far more per event than the runs of lines and DDA circles
/// (the configuration's `max_event_rate`: [`crate::stepper::MAX_STEP_RATE`], or less
/// for long step pulses). Out of line: inlined, it grew the planning task's deepest
/// stack frame.
#[inline(never)]
fn event_cap(cfg: &PlannerConfig, mv: &Move) -> f32 {
    let one_by_one = match mv.path {
        Path::Ellipse { .. } | Path::Sine { .. } => true,
        Path::Arc { .. } | Path::ArcFine { .. } => cfg.method == Method::Classic,
        Path::Line | Path::LineFine { .. } => false,
    };
    if one_by_one {
        MAX_SINGLE_EVENT_RATE.min(cfg.max_event_rate)
    } else {
        cfg.max_event_rate
    }
}

/// Step events (interpolation ticks) per mm of path along `mv` (of `length` mm), at
/// most: a line's ticks over its length (DDA: its longest axis travel; point by point:
/// every axis' travel); a curve's bound (DDA: a tick moves at least one step of some
/// axis, so at most the largest steps per mm; point by point, one axis per tick, at
/// most sqrt 2 times that).
fn events_per_mm(cfg: &PlannerConfig, start: StepPos, mv: &Move, length: f32) -> f32 {
    let classic = cfg.method == Method::Classic;
    match mv.path {
        Path::Line | Path::LineFine { .. } => {
            let travel = |i: usize| mv.target[i].wrapping_sub(start[i]).unsigned_abs() as f32;
            let ticks = if classic {
                travel(X) + travel(Y) + travel(Z)
            } else {
                travel(X).max(travel(Y)).max(travel(Z))
            };
            ticks / length
        }
        _ => sp(cfg, X).max(sp(cfg, Y)) * if classic { SQRT_2 } else { 1.0 },
    }
}

/// The shape of `mv` starting at `start`: its length, tangents, and the limits the
/// axes set.
fn shape_of(cfg: &PlannerConfig, start: StepPos, mv: &Move) -> Result<Geometry, GeometryError> {
    // Travels below 2^31 (both ends within motion::POS_LIMIT, checked by the planner
    // first): i32 differences, the same f32 as through i64.
    let d: [f32; AXES] =
        core::array::from_fn(|i| mv.target[i].wrapping_sub(start[i]) as f32 / sp(cfg, i));
    match mv.path {
        Path::Line | Path::LineFine { .. } => {
            let (length, u) = length_and_unit(d);
            if length <= 0.0 {
                return Err(GeometryError::Empty);
            }
            let (accel, speed_limit) = axis_limits(cfg, u);
            Ok(Geometry {
                length,
                unit_start: u,
                unit_end: u,
                accel,
                speed_limit,
            })
        }
        Path::Arc { center, ccw, turns } => {
            // A circle is the ellipse a = b = R (in steps, as the interpolator traces it).
            let p0 = (-center[0] as f32, -center[1] as f32);
            let r = crate::fmath::hypot(p0.0, p0.1);
            conic(cfg, start, mv, p0, r, r, ccw, turns)
        }
        Path::ArcFine {
            from,
            center,
            ccw,
            turns,
        } => {
            // The circle through the exact start; the start position is where the
            // machine is (the exact start rounded).
            let q = 1.0 / 256.0;
            let exact = (
                from[0].wrapping_sub(center[0]) as f32 * q,
                from[1].wrapping_sub(center[1]) as f32 * q,
            );
            let r = crate::fmath::hypot(exact.0, exact.1);
            let p0 = (
                (i64::from(start[X]) * 256 - i64::from(center[0])) as f32 * q,
                (i64::from(start[Y]) * 256 - i64::from(center[1])) as f32 * q,
            );
            conic(cfg, start, mv, p0, r, r, ccw, turns)
        }
        Path::Ellipse { center, a, b, ccw } => {
            let p0 = (-center[0] as f32, -center[1] as f32);
            conic(cfg, start, mv, p0, a as f32, b as f32, ccw, 0)
        }
        Path::Sine { amp, omega, phase } => {
            planar(start, mv)?;
            if d[X] == 0.0 || !(amp.is_finite() && omega.is_finite() && phase.is_finite()) {
                return Err(GeometryError::Invalid);
            }
            let dx = mv.target[X].wrapping_sub(start[X]) as f32;
            let dir = dx.signum();
            let periods = crate::decimal::to_u32(omega.abs() * dx.abs() / TAU);
            let curv = (amp * omega * omega).abs();
            let c = CurveVelocity {
                sx: sp(cfg, X),
                sy: sp(cfg, Y),
                x0: dir,
                xa: 0.0,
                ya: dir * (amp * omega),
                sign: 1.0,
                theta0: phase,
                w: omega,
                span: dx,
            };
            Ok(c.geometry(
                cfg,
                (periods.saturating_mul(16)).clamp(64, 4096) & !1,
                dx.abs(),
                [0.0; 2],
                1.0 / curv,
            ))
        }
    }
}

/// Geometry of a circular (`a == b`) or elliptical arc with semi-axes `a`, `b` (steps)
/// from `p0` (the start relative to the centre, steps), through the same sampler as
/// the sine: an exact circle
/// needs only its two ends and middle (its speed is constant), an ellipse 128 samples.
/// On both, the tangent is axis-aligned at parameter angles k * pi/2: where the sweep
/// passes one, that axis' tangent component reaches 1.
#[allow(clippy::too_many_arguments)]
fn conic(
    cfg: &PlannerConfig,
    start: StepPos,
    mv: &Move,
    p0: (f32, f32),
    af: f32,
    bf: f32,
    ccw: bool,
    turns: u16,
) -> Result<Geometry, GeometryError> {
    planar(start, mv)?;
    if !(af > 0.0 && bf > 0.0) {
        return Err(GeometryError::Invalid);
    }
    let p1 = (
        p0.0 + (mv.target[X] - start[X]) as f32,
        p0.1 + (mv.target[Y] - start[Y]) as f32,
    );
    let t0 = crate::fmath::atan2(p0.1 / bf, p0.0 / af);
    let t1 = crate::fmath::atan2(p1.1 / bf, p1.0 / af);
    let sweep = sweep(t0, t1, ccw, mv.target == start) + TAU * f32::from(turns);
    let sign = if ccw { 1.0 } else { -1.0 };
    let mut axis = [0.0f32; 2];
    for k in 0..4u8 {
        let at = f32::from(k) * (PI / 2.0);
        if wrap((at - t0) * sign) <= sweep {
            // Even k: a point on the X axis, tangent along Y; odd k: along X.
            axis[usize::from(k & 1 == 0)] = 1.0;
        }
    }
    let c = CurveVelocity {
        sx: sp(cfg, X),
        sy: sp(cfg, Y),
        x0: 0.0,
        xa: -af,
        ya: bf,
        sign,
        theta0: t0,
        w: 1.0,
        span: sign * sweep,
    };
    // Smallest radius of curvature of an ellipse: min(a^2/b, b^2/a) (steps).
    let r_min = (af * af / bf).min(bf * bf / af);
    Ok(c.geometry(cfg, if af == bf { 2 } else { 128 }, sweep, axis, r_min))
}

fn planar(start: StepPos, mv: &Move) -> Result<(), GeometryError> {
    if start[Z] == mv.target[Z] {
        Ok(())
    } else {
        Err(GeometryError::Invalid)
    }
}

/// Angle wrapped into [0, 2 pi), negative angles too (`%` would keep the sign).
fn wrap(a: f32) -> f32 {
    let w = a - crate::fmath::floor(a / TAU) * TAU;
    if w >= TAU {
        0.0
    } else {
        w.max(0.0)
    }
}

/// Angle swept from `a0` to `a1` in the given direction, in (0, 2 pi]; a closed curve
/// (`full`) sweeps 2 pi.
fn sweep(a0: f32, a1: f32, ccw: bool, full: bool) -> f32 {
    if full {
        return TAU;
    }
    let s = if ccw { wrap(a1 - a0) } else { wrap(a0 - a1) };
    if s <= 0.0 {
        TAU
    } else {
        s
    }
}

/// A planar curve's velocity in mm per parameter unit, one form for ellipses and
/// sines (one sampler instead of a copy per curve): at parameter theta =
/// theta0 + w * (span * i / n), velocity = ((x0 + xa sin theta) / sx * sign,
/// ya cos theta / sy * sign).
struct CurveVelocity {
    sx: f32,
    sy: f32,
    x0: f32,
    xa: f32,
    ya: f32,
    sign: f32,
    theta0: f32,
    w: f32,
    span: f32,
}

impl CurveVelocity {
    fn vel(&self, i: u32, n: u32) -> [f32; AXES] {
        let theta = self.theta0 + self.w * (self.span * i as f32 / n as f32);
        let (sin, cos) = crate::fmath::sin_cos(theta);
        [
            (self.x0 + self.xa * sin) / self.sx * self.sign,
            self.ya * cos / self.sy * self.sign,
            0.0,
        ]
    }
}

impl CurveVelocity {
    /// Simpson integral of |vel(t)| over a parameter span `span` sampled at n (even)
    /// intervals, the tightest per-axis limits over the samples (and `axis`, known
    /// largest tangent components), the centripetal limit at the smallest radius of
    /// curvature `r_min` (steps), and the end tangents.
    fn geometry(
        &self,
        cfg: &PlannerConfig,
        n: u32,
        span: f32,
        axis: [f32; 2],
        r_min: f32,
    ) -> Geometry {
        let mut sum = 0.0f32;
        let mut most = [axis[0], axis[1], 0.0];
        for i in 0..=n {
            let v = self.vel(i, n);
            let (m, u) = length_and_unit(v);
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            sum += w * m;
            // min over samples of min_i a_i / |u_i| is min_i a_i / max over samples |u_i|.
            most = [
                most[X].max(u[X].abs()),
                most[Y].max(u[Y].abs()),
                most[Z].max(u[Z].abs()),
            ];
        }
        let (accel, speed) = axis_limits(cfg, most);
        let r_min = r_min / self.sx.max(self.sy);
        Geometry {
            length: sum * span / (3.0 * n as f32),
            unit_start: length_and_unit(self.vel(0, 1)).1,
            unit_end: length_and_unit(self.vel(1, 1)).1,
            accel,
            speed_limit: speed.min(crate::fmath::sqrt(accel * r_min)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Feed;
    use crate::stepper::MAX_STEP_RATE;

    fn mv(target: StepPos, path: Path) -> Move {
        Move {
            target,
            path,
            feed: Feed::MmPerMin(3000.0),
            line: 0,
        }
    }

    #[test]
    fn diagonal_line_accelerates_faster_along_the_path() {
        let cfg = PlannerConfig::default();
        let g = of_move(&cfg, [0; 3], &mv([800, 800, 0], Path::Line)).unwrap();
        assert!((g.length - 200f32.sqrt()).abs() < 1e-4);
        assert!((g.accel - 500.0 * 2f32.sqrt()).abs() < 0.1);
        assert!((g.speed_limit - 5000.0 / 60.0 * 2f32.sqrt()).abs() < 0.1);
    }

    #[test]
    fn events_timed_one_by_one_are_held_to_their_own_cap() {
        // 1280 steps/mm and fast axes: the step pipeline's caps bind, not the axes.
        let mut cfg = PlannerConfig::default();
        for a in &mut cfg.axes {
            a.steps_per_mm = 1280.0;
            a.max_rate = 100_000.0;
        }
        let circle = Path::Arc {
            center: [-12_800, 0],
            ccw: true,
            turns: 0,
        };
        let end = [-25_600, 0, 0];
        let dda = of_move(&cfg, [0; 3], &mv(end, circle)).unwrap();
        assert!((dda.speed_limit - MAX_STEP_RATE / 1280.0).abs() < 1e-3);
        cfg.method = Method::Classic;
        let classic = of_move(&cfg, [0; 3], &mv(end, circle)).unwrap();
        let single = MAX_SINGLE_EVENT_RATE / (1280.0 * SQRT_2);
        assert!((classic.speed_limit - single).abs() < 1e-3);
        // A point-by-point line is a run: the common cap, per event of its own.
        let line = of_move(&cfg, [0; 3], &mv([12_800, 12_800, 0], Path::Line)).unwrap();
        let per_mm = 25_600.0 / (10.0 * SQRT_2);
        assert!((line.speed_limit - MAX_STEP_RATE / per_mm).abs() < 1e-2);
        cfg.method = Method::Dda;
        let ellipse = Path::Ellipse {
            center: [-12_800, 0],
            a: 12_800,
            b: 10_000,
            ccw: true,
        };
        let e = of_move(&cfg, [0; 3], &mv(end, ellipse)).unwrap();
        assert!((e.speed_limit - MAX_SINGLE_EVENT_RATE / 1280.0).abs() < 1e-3);
    }

    #[test]
    fn long_step_pulses_lower_the_event_cap() {
        let mut cfg = PlannerConfig::default();
        for a in &mut cfg.axes {
            a.steps_per_mm = 800.0;
            a.max_rate = 100_000.0;
        }
        let line = mv([8_000, 0, 0], Path::Line);
        let at = |pulse_us: u8, cfg: &mut PlannerConfig| {
            cfg.max_event_rate = crate::stepper::event_rate_for_pulse(pulse_us);
            of_move(cfg, [0; 3], &line).unwrap().speed_limit * 800.0
        };
        // $0=10: 10 + 2 µs allow 83,333 events/s, above the pipeline's cap.
        assert!((at(10, &mut cfg) - MAX_STEP_RATE).abs() < 1.0);
        // $0=20: a period of at least 22 µs.
        assert!((at(20, &mut cfg) - 1e6 / 22.0).abs() < 1.0);
        assert!((at(255, &mut cfg) - 1e6 / 257.0).abs() < 0.1);
    }

    #[test]
    fn full_circle_length_and_limits() {
        let cfg = PlannerConfig::default();
        // R = 20 mm at 80 steps/mm, centre to the right of the start, clockwise.
        let g = of_move(
            &cfg,
            [0; 3],
            &mv(
                [0; 3],
                Path::Arc {
                    center: [1600, 0],
                    ccw: false,
                    turns: 0,
                },
            ),
        )
        .unwrap();
        assert!((g.length - TAU * 20.0).abs() < 1e-3);
        assert!((g.accel - 500.0).abs() < 1e-3);
        // Centripetal limit sqrt(500 * 20) = 100 mm/s, axis limit 83.3 mm/s.
        assert!((g.speed_limit - 5000.0 / 60.0).abs() < 1e-3);
        // Tangent at the start points up (clockwise around a centre on the right).
        assert!((g.unit_start[1] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn quarter_arc_and_ellipse_and_sine_lengths() {
        let cfg = PlannerConfig::default();
        let q = of_move(
            &cfg,
            [800, 0, 0],
            &mv(
                [0, 800, 0],
                Path::Arc {
                    center: [-800, 0],
                    ccw: true,
                    turns: 0,
                },
            ),
        )
        .unwrap();
        assert!((q.length - PI * 10.0 / 2.0).abs() < 1e-3);
        // Circle as an ellipse a = b: same length.
        let e = of_move(
            &cfg,
            [800, 0, 0],
            &mv(
                [800, 0, 0],
                Path::Ellipse {
                    center: [-800, 0],
                    a: 800,
                    b: 800,
                    ccw: true,
                },
            ),
        )
        .unwrap();
        assert!((e.length - TAU * 10.0).abs() < 1e-2);
        // Ellipse a = 2b: perimeter ~ 9.6884 b (Ramanujan).
        let e2 = of_move(
            &cfg,
            [1600, 0, 0],
            &mv(
                [1600, 0, 0],
                Path::Ellipse {
                    center: [-1600, 0],
                    a: 1600,
                    b: 800,
                    ccw: false,
                },
            ),
        )
        .unwrap();
        assert!((e2.length - 96.884).abs() < 0.05, "{}", e2.length);
        // Flat sine: length equals the X travel.
        let s = of_move(
            &cfg,
            [0; 3],
            &mv(
                [800, 0, 0],
                Path::Sine {
                    amp: 0.0,
                    omega: 0.1,
                    phase: 0.0,
                },
            ),
        )
        .unwrap();
        assert!((s.length - 10.0).abs() < 1e-4);
        assert_eq!(
            of_move(&cfg, [0; 3], &mv([0; 3], Path::Line)),
            Err(GeometryError::Empty)
        );
    }
}
