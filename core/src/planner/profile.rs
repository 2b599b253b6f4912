//! Velocity profiles of one block: ramp, cruise, ramp, from any current state.
//!
//! Owns the speed-versus-time law and nothing else. Two ramp shapes:
//! - [`Shape::Trapezoid`]: constant acceleration `a` (Grbl's behaviour).
//! - [`Shape::Cosine`]: the thesis's S-curve (seed 001, ch. 3),
//!   v(t) = v0 + (v1 - v0)/2 (1 - cos(pi t / T)): acceleration is continuous and peaks
//!   at `a` in the middle of the ramp, so T = pi |v1 - v0| / (2 a).
//!
//! Both ramps cover (v0 + v1)/2 * T, so a cosine ramp needs the distance of a
//! trapezoid ramp at the "effective" acceleration 2a/pi. The planner therefore plans
//! with [`Shape::effective_accel`] and one formula serves both shapes.
//!
//! A profile is built from the present state (speed `v0` with `dist` left to go) so the
//! step engine can rebuild it at any time: after a re-plan, a feed hold, or an override.

use core::f32::consts::PI;

/// Ramp shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Shape {
    #[default]
    Trapezoid,
    /// Jerk-limited cosine ramp (S-curve).
    Cosine,
}

impl Shape {
    /// The constant acceleration that covers the same distance per ramp.
    pub fn effective_accel(self, a: f32) -> f32 {
        match self {
            Shape::Trapezoid => a,
            Shape::Cosine => a * (2.0 / PI),
        }
    }
}

/// One ramp from `v0` to `v1` lasting `t` seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ramp {
    v0: f32,
    v1: f32,
    t: f32,
}

impl Ramp {
    /// A ramp from `v0` to `v1` at peak acceleration `1 / inv_a`.
    fn new(shape: Shape, v0: f32, v1: f32, inv_a: f32) -> Self {
        let t = match shape {
            Shape::Trapezoid => (v1 - v0).abs() * inv_a,
            Shape::Cosine => 0.5 * PI * (v1 - v0).abs() * inv_a,
        };
        Ramp { v0, v1, t }
    }
    fn dist(&self) -> f32 {
        0.5 * (self.v0 + self.v1) * self.t
    }
    /// Distance and speed `t` seconds into the ramp. The second half is evaluated
    /// backwards from the end (a ramp run backwards is the reverse ramp), so the
    /// distance left near the end keeps full precision with f32 sine/cosine.
    fn at(&self, shape: Shape, t: f32) -> (f32, f32) {
        if self.t <= 0.0 {
            return (0.0, self.v0);
        }
        if t > 0.5 * self.t {
            let rev = Ramp {
                v0: self.v1,
                v1: self.v0,
                t: self.t,
            };
            let (d, v, _) = rev.forward(shape, (self.t - t).max(0.0));
            return (self.dist() - d, v);
        }
        let (d, v, _) = self.forward(shape, t);
        (d, v)
    }

    /// Distance, speed and acceleration `t` seconds into the ramp, from its start.
    fn forward(&self, shape: Shape, t: f32) -> (f32, f32, f32) {
        let dv = self.v1 - self.v0;
        match shape {
            Shape::Trapezoid => {
                let acc = dv / self.t;
                (self.v0 * t + 0.5 * acc * t * t, self.v0 + acc * t, acc)
            }
            Shape::Cosine => {
                let w = PI / self.t;
                let (sin, cos) = crate::fmath::sin_cos(w * t);
                let s = self.v0 * t + 0.5 * dv * (t - sin / w);
                (s, self.v0 + 0.5 * dv * (1.0 - cos), 0.5 * dv * w * sin)
            }
        }
    }
}

/// Newton's step on a cosine ramp's time below which it has converged, relative to the
/// ramp's length: one ulp of f32 at the ramp's end (of a 0.1 s ramp 7 ns, half a tick
/// of the 72 MHz step timer), what a bracket of two neighbouring floats always reaches.
const TIME_EPS: f32 = f32::EPSILON;

/// A point of a phase near the one asked for (the last answer in that phase): its
/// phase-local time and distance and the speed there, as [`Profile::phase_time`]
/// gives and takes them. Newton's method on an S-curve's ramp starts from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Near {
    pub t: f32,
    pub d: f32,
    pub v: f32,
}

impl Ramp {
    /// Time into the ramp at which it has covered `d` (0 <= d <= dist), and the speed
    /// there; `near`: a known point of this ramp near the answer.
    ///
    /// Trapezoid: closed form, t = 2 d / (v0 + v) with v^2 = v0^2 + 2 a d (no
    /// cancellation at any speed). Cosine: the distance law has no inverse in closed
    /// form, so Newton's method on it, kept inside a shrinking bracket.
    fn time_for(&self, shape: Shape, d: f32, near: Option<Near>) -> (f32, f32) {
        if self.t <= 0.0 || d <= 0.0 {
            return (0.0, self.v0);
        }
        match shape {
            Shape::Trapezoid => self.trapezoid_time_for(d),
            Shape::Cosine => {
                let (mut lo, mut hi) = (0.0f32, self.t);
                // From a known point near the answer: Newton's first step from there,
                // taken without evaluating the ramp (its distance and speed are known).
                // With the stop below, a step's time then takes one evaluation of the
                // ramp (a sine and a cosine) in most calls, 1.2 on average, instead of
                // three (seed 2056649456 below: 907 against 2,308): an S-curve's ticks
                // timed one by one (point by point, `$212=0`) cost 11,000
                // instructions each, and kept the image's step queue short of steps at
                // 3,000 steps/s under the pessimistic cycle model (`.ci/emu-random`,
                // seed 2056649456). Without one (a phase's first step), the
                // trapezoid's closed form at the same mean acceleration: from t = 0 at a
                // slow start speed, Newton's first step overshoots the ramp and
                // bisection takes ~20 rounds.
                let mut t = match near {
                    Some(n) if n.t > 0.0 && n.v > 0.0 => {
                        (n.t + (d - n.d) / n.v).max(0.0).min(self.t)
                    }
                    Some(n) if n.t > 0.0 => n.t.min(self.t),
                    _ => self.trapezoid_time_for(d).0,
                };
                let tolerance = TIME_EPS * self.t;
                let peak_accel = self.derivative_bounds(shape)[0];
                for _ in 0..40 {
                    let (s, v, a) = self.forward(shape, t);
                    let f = s - d;
                    if f > 0.0 {
                        hi = t;
                    } else {
                        lo = t;
                    }
                    if crate::fmath::abs(f) <= 1e-7 * d.max(1e-3) || hi - lo <= tolerance {
                        return (t, v);
                    }
                    let step = if v > 0.0 { f / v } else { 0.0 };
                    let next = if v > 0.0 { t - step } else { -1.0 };
                    // Newton's step lands within a|step|^2 / 2v of the root, `a` the
                    // largest acceleration between (the distance's curvature over its
                    // slope; the ramp's peak bounds it): when that is under the
                    // tolerance, it is the answer, and the speed there follows from
                    // the acceleration (its change over the step is of the same
                    // order). From a near point's first-order guess this is the
                    // usual case: one evaluation instead of two.
                    if v > 0.0
                        && next > lo
                        && next < hi
                        && peak_accel * step * step <= 2.0 * v * tolerance
                    {
                        return (next, v - a * step);
                    }
                    // Converged too when Newton's step is below f32's resolution of
                    // the ramp's time: at the root `f` is an ulp of `s` or so, and the
                    // step lands on `t` itself, at the bracket's end. Without this,
                    // such a call bisected until the bracket reached 1e-9 of the
                    // ramp, under f32's resolution: all 40 rounds (~110,000
                    // instructions, 1.5 ms on the image, where the step queue ran dry:
                    // S-curve jobs 3-4 % longer than in the simulator, issue 23).
                    if crate::fmath::abs(next - t) <= tolerance {
                        return (t, v);
                    }
                    t = if next > lo && next < hi {
                        next
                    } else {
                        0.5 * (lo + hi)
                    };
                }
                (t, self.forward(shape, t).1)
            }
        }
    }

    /// [`Ramp::time_for`] of a trapezoid ramp (`d > 0`, `self.t > 0`).
    fn trapezoid_time_for(&self, d: f32) -> (f32, f32) {
        let acc = (self.v1 - self.v0) / self.t;
        let v = crate::fmath::sqrt((self.v0 * self.v0 + 2.0 * acc * d).max(0.0));
        let sum = self.v0 + v;
        let t = if sum > 0.0 { 2.0 * d / sum } else { 0.0 };
        (t.min(self.t), v)
    }

    /// Bounds of |acceleration|, |jerk| and |d jerk/dt| along the ramp (mm/s^2, /s^3,
    /// /s^4): what the step timing's error bound needs.
    fn derivative_bounds(&self, shape: Shape) -> [f32; 3] {
        if self.t <= 0.0 {
            return [0.0; 3];
        }
        let dv = crate::fmath::abs(self.v1 - self.v0);
        match shape {
            Shape::Trapezoid => [dv / self.t, 0.0, 0.0],
            Shape::Cosine => {
                let w = PI / self.t;
                let a = 0.5 * dv * w;
                [a, a * w, a * w * w]
            }
        }
    }
}

/// One of a profile's three phases.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// The first ramp (to the peak speed; down if the speed was above it).
    Up,
    Cruise,
    /// The last ramp, timed back from the profile's end.
    Down,
}

/// A ramp-cruise-ramp profile over a known distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profile {
    shape: Shape,
    /// Peak acceleration of the ramps.
    accel: f32,
    up: Ramp,
    cruise_v: f32,
    cruise_t: f32,
    down: Ramp,
}

impl Profile {
    /// Fastest profile from speed `v0` over `dist` that ends at `v_exit`, never above
    /// `v_max`, with peak acceleration `a`. If `v_exit` cannot be reached (too short to
    /// slow down, or to speed up), the profile ends at the closest reachable speed.
    pub fn new(shape: Shape, v0: f32, v_max: f32, v_exit: f32, a: f32, dist: f32) -> Self {
        let a = if a > 0.0 { a } else { f32::MIN_POSITIVE };
        let ae = shape.effective_accel(a);
        let dist = dist.max(0.0);
        let v0 = v0.max(0.0);
        let v_max = v_max.max(0.0);
        // Exit speeds reachable over `dist` from v0 lie in [lo, hi] (compared as squares:
        // a root only where the bound applies; this runs once per block).
        let hi2 = v0 * v0 + 2.0 * ae * dist;
        let lo2 = v0 * v0 - 2.0 * ae * dist;
        let ve = v_exit.max(0.0);
        let ve = if ve * ve > hi2 {
            crate::fmath::sqrt(hi2)
        } else if ve * ve < lo2 {
            crate::fmath::sqrt(lo2)
        } else {
            ve
        };
        // Where an acceleration from v0 meets a deceleration to ve (>= both of them).
        let meet2 = ae * dist + 0.5 * (v0 * v0 + ve * ve);
        let peak = if meet2 <= v_max * v_max {
            crate::fmath::sqrt(meet2)
        } else {
            v_max.max(ve)
        };
        let inv_a = 1.0 / a;
        let up = Ramp::new(shape, v0, peak, inv_a);
        let down = Ramp::new(shape, peak, ve, inv_a);
        let cruise_d = (dist - up.dist() - down.dist()).max(0.0);
        let cruise_t = if peak > 0.0 { cruise_d / peak } else { 0.0 };
        Profile {
            shape,
            accel: a,
            up,
            cruise_v: peak,
            cruise_t,
            down,
        }
    }

    /// At rest with nothing to cover: what [`Profile::new`] gives for no distance and
    /// no speed at an acceleration of 1 (a placeholder until the first real profile).
    pub fn rest(shape: Shape) -> Self {
        let r = Ramp {
            v0: 0.0,
            v1: 0.0,
            t: 0.0,
        };
        Profile {
            shape,
            accel: 1.0,
            up: r,
            cruise_v: 0.0,
            cruise_t: 0.0,
            down: r,
        }
    }

    /// Distance covered when the first ramp ends and when the cruise ends.
    pub fn phase_ends(&self) -> (f32, f32) {
        let up = self.up.dist();
        (up, up + self.cruise_v * self.cruise_t)
    }

    /// [`Profile::phase_ends`] and [`Profile::distance`] at once (each ramp's distance
    /// evaluated once).
    pub fn phase_ends_and_distance(&self) -> (f32, f32, f32) {
        let (e0, e1) = self.phase_ends();
        (e0, e1, e1 + self.down.dist())
    }

    /// Duration of each phase, seconds.
    pub fn phase_durations(&self) -> [f32; 3] {
        [self.up.t, self.cruise_t, self.down.t]
    }

    /// Phase-local time and the speed there: for [`Phase::Up`] the time from the
    /// profile's start at which it has covered `d` (mm from the start); for
    /// [`Phase::Cruise`] the time from the cruise's start at `d` mm into the cruise; for
    /// [`Phase::Down`] the time left to the end when `d` mm are left. Each is computed
    /// from its own end of the phase so that small distances near a slow end keep their
    /// precision. `near`: a known point of this phase near the answer.
    pub fn phase_time(&self, phase: Phase, d: f32, near: Option<Near>) -> (f32, f32) {
        let d = d.max(0.0);
        match phase {
            Phase::Up => self.up.time_for(self.shape, d.min(self.up.dist()), near),
            Phase::Cruise => {
                let t = if self.cruise_v > 0.0 {
                    d / self.cruise_v
                } else {
                    0.0
                };
                (t, self.cruise_v)
            }
            Phase::Down => {
                let rev = Ramp {
                    v0: self.down.v1,
                    v1: self.down.v0,
                    t: self.down.t,
                };
                rev.time_for(self.shape, d.min(rev.dist()), near)
            }
        }
    }

    /// Bounds of |acceleration|, |jerk| and |d jerk/dt| within `phase`.
    pub fn derivative_bounds(&self, phase: Phase) -> [f32; 3] {
        let ramp = match phase {
            Phase::Up => self.up,
            Phase::Cruise => return [0.0; 3],
            Phase::Down => self.down,
        };
        match self.shape {
            // A trapezoid's ramps run at the acceleration itself (no division).
            Shape::Trapezoid if ramp.t > 0.0 => [self.accel, 0.0, 0.0],
            _ => ramp.derivative_bounds(self.shape),
        }
    }

    /// The ramps' shape.
    pub fn shape(&self) -> Shape {
        self.shape
    }

    /// Speed at the start and at the end of `phase`.
    pub fn phase_speeds(&self, phase: Phase) -> (f32, f32) {
        match phase {
            Phase::Up => (self.up.v0, self.up.v1),
            Phase::Cruise => (self.cruise_v, self.cruise_v),
            Phase::Down => (self.down.v0, self.down.v1),
        }
    }

    /// Whether the speed rises (or stays) through `phase`.
    pub fn phase_rises(&self, phase: Phase) -> bool {
        match phase {
            Phase::Up => self.up.v1 >= self.up.v0,
            Phase::Cruise => true,
            Phase::Down => self.down.v1 >= self.down.v0,
        }
    }

    /// Total duration in seconds.
    pub fn duration(&self) -> f32 {
        self.up.t + self.cruise_t + self.down.t
    }
    /// Total distance.
    pub fn distance(&self) -> f32 {
        self.up.dist() + self.cruise_v * self.cruise_t + self.down.dist()
    }
    /// Speed at the end.
    pub fn exit_speed(&self) -> f32 {
        self.down.v1
    }
    /// Distance left to the end `t` seconds after the start. Near the end it comes from
    /// the last ramp run backwards, so it keeps full f32 precision where the speed is
    /// low and a tiny distance error would be a large time error (`distance() - at(t)`
    /// would lose it to cancellation).
    pub fn left(&self, t: f32) -> f32 {
        let r = self.duration() - t;
        if r < self.down.t {
            let rev = Ramp {
                v0: self.down.v1,
                v1: self.down.v0,
                t: self.down.t,
            };
            rev.at(self.shape, r.max(0.0)).0
        } else {
            (self.distance() - self.at(t).0).max(0.0)
        }
    }
    /// Distance covered and speed `t` seconds after the start (clamped to the end).
    pub fn at(&self, t: f32) -> (f32, f32) {
        let t = t.max(0.0);
        if t < self.up.t {
            return self.up.at(self.shape, t);
        }
        let d_up = self.up.dist();
        let t = t - self.up.t;
        if t < self.cruise_t {
            return (d_up + self.cruise_v * t, self.cruise_v);
        }
        let d_cr = self.cruise_v * self.cruise_t;
        let t = (t - self.cruise_t).min(self.down.t);
        let (d, v) = self.down.at(self.shape, t);
        (d_up + d_cr + d, v)
    }
}

/// The time at which an S-curve's ramp from `v0`, changing speed by `dv` in `t_end`
/// seconds, has covered `d`: in f64, by bisection, the tests' reference.
#[cfg(test)]
pub(crate) fn reference_ramp_time(v0: f64, dv: f64, t_end: f64, d: f64) -> f64 {
    let w = core::f64::consts::PI / t_end;
    let s = |t: f64| v0 * t + 0.5 * dv * (t - (w * t).sin() / w);
    let (mut lo, mut hi) = (0.0, t_end);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_worked_example_reaches_20_khz_at_two_seconds() {
        // 1 s cosine ramp to 100 rev/s, 500 rev in total, 200 pulses per rev.
        // Peak acceleration of a 1 s cosine ramp of 100 rev/s: pi * 100 / 2.
        let a = PI * 100.0 / 2.0;
        let p = Profile::new(Shape::Cosine, 0.0, 100.0, 0.0, a, 500.0);
        assert!((p.duration() - 6.0).abs() < 1e-3, "{}", p.duration());
        let (s, v) = p.at(2.0);
        assert!((v * 200.0 - 20_000.0).abs() < 1.0, "{}", v * 200.0);
        // 50 rev in the ramp, then one second of cruise.
        assert!((s - 150.0).abs() < 1e-2, "{}", s);
        let (_, v_half) = p.at(0.5);
        assert!((v_half - 50.0).abs() < 1e-3);
        let (s_end, v_end) = p.at(6.0);
        assert!((s_end - 500.0).abs() < 1e-2 && v_end.abs() < 1e-3);
    }

    #[test]
    fn rest_is_the_empty_profile() {
        for shape in [Shape::Trapezoid, Shape::Cosine] {
            assert_eq!(
                Profile::rest(shape),
                Profile::new(shape, 0.0, 0.0, 0.0, 1.0, 0.0)
            );
        }
    }

    #[test]
    fn trapezoid_and_triangle() {
        // 100 mm at up to 50 mm/s with 500 mm/s^2: 0.1 s ramps, 2.1 s total.
        let p = Profile::new(Shape::Trapezoid, 0.0, 50.0, 0.0, 500.0, 100.0);
        assert!((p.duration() - 2.1).abs() < 1e-4);
        // 1 mm is too short to reach 50 mm/s: triangle peaking at sqrt(a d).
        let t = Profile::new(Shape::Trapezoid, 0.0, 50.0, 0.0, 500.0, 1.0);
        let (_, vp) = t.at(t.duration() / 2.0);
        assert!((vp - 500f32.sqrt()).abs() < 1e-3);
        assert!((t.distance() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn from_any_state_brakes_when_too_fast() {
        // Feed hold: from 40 mm/s stop as soon as possible, with plenty of room.
        let p = Profile::new(Shape::Trapezoid, 40.0, 0.0, 0.0, 500.0, 1000.0);
        // f32 profile: 1.6 to within a few ulp (was 1e-9 while the profile was f64).
        assert!((p.distance() - 1.6).abs() < 1e-6 && p.exit_speed() == 0.0);
        // Too short to stop: ends at the lowest reachable speed.
        let q = Profile::new(Shape::Trapezoid, 40.0, 40.0, 0.0, 500.0, 1.0);
        assert!((q.exit_speed() - (1600.0f32 - 1000.0).sqrt()).abs() < 1e-3);
        assert!((q.distance() - 1.0).abs() < 1e-4);
        // Override lowered the maximum below the present speed.
        let r = Profile::new(Shape::Cosine, 40.0, 20.0, 20.0, 500.0, 100.0);
        assert!((r.at(r.duration() * 0.5).1 - 20.0).abs() < 1e-3);
        assert!((r.distance() - 100.0).abs() < 1e-3);
    }

    #[test]
    fn speed_is_monotone_on_ramps_and_distance_never_decreases() {
        for shape in [Shape::Trapezoid, Shape::Cosine] {
            let p = Profile::new(shape, 5.0, 80.0, 10.0, 300.0, 40.0);
            let mut last = -1.0f32;
            for i in 0..=1000 {
                let (s, _) = p.at(p.duration() * i as f32 / 1000.0);
                assert!(s >= last - 1e-5);
                last = s;
            }
            assert!((last - 40.0).abs() < 1e-3);
        }
    }

    /// The time of a distance on an S-curve's ramp, in f64.
    fn reference_time(r: &Ramp, d: f64) -> f64 {
        reference_ramp_time(f64::from(r.v0), f64::from(r.v1 - r.v0), f64::from(r.t), d)
    }

    proptest::proptest! {
        /// Step by step along an S-curve's ramps, as the preparation times ticks one
        /// by one (each from the last answer, [`Near`]): every time within what f32
        /// can say of it (the distance's rounding over the speed, and the ramp's time
        /// to a few ulps) of the exact one, and never worse than a call without a
        /// near point.
        #[test]
        fn s_curve_times_from_a_near_point_are_exact(
            v0 in 0.0f32..40.0, v_max in 5.0f32..120.0, accel in 50.0f32..3000.0,
            dist in 0.5f32..40.0, step in 0.005f32..0.1,
        ) {
            let p = Profile::new(Shape::Cosine, v0, v_max, 0.0, accel, dist);
            for (phase, ramp) in [(Phase::Up, p.up), (Phase::Down, Ramp { v0: p.down.v1, v1: p.down.v0, t: p.down.t })] {
                let mut near: Option<Near> = None;
                let mut d = step;
                while d < ramp.dist() {
                    let (t, v) = p.phase_time(phase, d, near);
                    let (t_alone, _) = p.phase_time(phase, d, None);
                    let exact = reference_time(&ramp, f64::from(d));
                    let resolution = 4.0 * f64::from(d) * f64::from(f32::EPSILON) / f64::from(v.max(1e-3))
                        + 4.0 * f64::from(ramp.t) * f64::from(f32::EPSILON);
                    let err = (f64::from(t) - exact).abs();
                    proptest::prop_assert!(err <= resolution.max((f64::from(t_alone) - exact).abs()),
                        "{phase:?} d {d}: {t} s, exact {exact} s, alone {t_alone} s");
                    let (_, v_exact) = ramp.at(Shape::Cosine, exact as f32);
                    proptest::prop_assert!((v - v_exact).abs() <= 1e-4 * v_exact.max(1.0), "speed {v} against {v_exact}");
                    near = Some(Near { t, d, v });
                    d += step;
                }
            }
        }
    }
}
