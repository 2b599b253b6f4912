//! y = f(x) traced column by column: the sine of the lab report (3.8) and any other
//! function over [x1, x2].
//!
//! The walk samples f at every integer and half-integer x (two evaluations per
//! column). From (k, Y_k), with Y_k the integer nearest f(k), it climbs at column k to
//! the integer nearest f(k + 1/2) (the rows the curve enters before leaving the
//! column), crosses to column k + 1 and climbs on to Y_{k+1}. Every visited grid point
//! is then within half a step of the curve on both axes, provided f is monotonic on
//! each half column (true for any sine with a period above two steps). In DDA mode
//! the column crossing is merged with one climbing step into a diagonal step event; in
//! classic mode every step event moves one axis.
//!
//! Evaluation uses f32 ([`crate::fmath`]); this runs in the segment-preparation task,
//! never in the step interrupt.

use super::line::Line;
use super::{event_xy, InterpError, Interpolate, Method, StepEvent};
use crate::motion::{StepPos, X, Y};

/// Largest sine amplitude, steps (2^28, 3.3 km at 80 steps/mm).
const AMP_LIMIT: f32 = 268_435_456.0;

/// A function y = f(u), u = x - x_start in steps, y relative to the start in steps.
pub trait Curve {
    fn eval(&self, u: f32) -> f32;
    /// dy/du; a central difference unless the curve knows better.
    fn slope(&self, u: f32) -> f32 {
        self.eval(u + 0.25) * 2.0 - self.eval(u - 0.25) * 2.0
    }
}

impl<F: Fn(f32) -> f32> Curve for F {
    fn eval(&self, u: f32) -> f32 {
        self(u)
    }
}

/// y = amp sin(omega u + phase) - amp sin(phase): passes through the start point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sine {
    amp: f32,
    omega: f32,
    phase: f32,
    offset: f32,
}

impl Sine {
    pub fn new(amp: f32, omega: f32, phase: f32) -> Result<Self, InterpError> {
        if !(amp.is_finite() && omega.is_finite() && phase.is_finite()) {
            return Err(InterpError::Degenerate);
        }
        // |f| <= 2 |amp| < 2^29: rows and their differences fit the trace's i32.
        if amp.abs() >= AMP_LIMIT {
            return Err(InterpError::TooLarge);
        }
        Ok(Sine {
            amp,
            omega,
            phase,
            offset: amp * crate::fmath::sin_cos(phase).0,
        })
    }
}

impl Curve for Sine {
    fn eval(&self, u: f32) -> f32 {
        self.amp * crate::fmath::sin_cos(self.omega * u + self.phase).0 - self.offset
    }
    fn slope(&self, u: f32) -> f32 {
        self.amp * self.omega * crate::fmath::sin_cos(self.omega * u + self.phase).1
    }
}

/// Column walk along y = f(x) from the start's X to the target's X, then a straight
/// tail to the exact integer target (nothing when the target is the curve's nearest
/// point, which is the normal case).
#[derive(Clone, Debug)]
pub struct CurveTrace<C> {
    curve: C,
    /// +1 or -1: direction of x.
    dir: i32,
    /// Columns to walk (below 2^31: moves stay within motion::POS_LIMIT).
    cols: i32,
    /// Current column (relative) and row (relative to the start).
    k: i32,
    y: i32,
    /// Rows still to climb before the column crossing, and after it.
    first: i32,
    second: i32,
    /// The crossing step event of the current column is still to come.
    crossing: bool,
    method: Method,
    /// Exact target relative to the start.
    end: (i32, i32),
    tail: Option<Line>,
}

fn nearest(v: f32) -> i32 {
    // Saturating conversion; NaN becomes 0.
    crate::decimal::round_i32(v)
}

impl<C: Curve> CurveTrace<C> {
    pub fn new(start: StepPos, target: StepPos, curve: C, method: Method) -> Self {
        // Wrapping: exact for moves within motion::POS_LIMIT.
        let dx = target[X].wrapping_sub(start[X]);
        let dy = target[Y].wrapping_sub(start[Y]);
        let mut t = CurveTrace {
            curve,
            dir: if dx < 0 { -1 } else { 1 },
            cols: dx.wrapping_abs(),
            k: 0,
            y: 0,
            first: 0,
            second: 0,
            crossing: false,
            method,
            end: (dx, dy),
            tail: None,
        };
        t.plan_column();
        t
    }

    /// Feed direction at the present column (step space, not normalised).
    pub fn direction(&self) -> [f32; 2] {
        let u = (self.dir * self.k) as f32 + 0.5 * self.dir as f32;
        [self.dir as f32, self.dir as f32 * self.curve.slope(u)]
    }

    /// Ideal path length per step event at the present column, mm (`spx`, `spy`: steps per
    /// mm): the tangent's length over the step events it takes (DDA: one per step of the
    /// larger component; classic: one per step of either).
    pub fn tick_len(&self, spx: f32, spy: f32) -> f32 {
        let [tx, ty] = self.direction();
        let (tx, ty) = (crate::fmath::abs(tx), crate::fmath::abs(ty));
        let (mx, my) = (tx / spx, ty / spy);
        let per = match self.method {
            Method::Dda => tx.max(ty),
            Method::Classic => tx + ty,
        };
        if per > 0.0 {
            crate::fmath::sqrt(mx * mx + my * my) / per
        } else {
            0.0
        }
    }

    fn at(&self, k2: i64) -> i32 {
        // f at u = dir * k2 / 2.
        nearest(self.curve.eval((i64::from(self.dir) * k2) as f32 * 0.5))
    }

    /// Sets up the climbs of column k -> k+1 (or the tail after the last column).
    fn plan_column(&mut self) {
        if self.k >= self.cols {
            self.crossing = false;
            let from = [0, self.y, 0];
            let to = [self.end.0.wrapping_sub(self.dir * self.k), self.end.1, 0];
            let to = [to[0].saturating_mul(self.dir), to[1], 0];
            self.tail = Some(Line::new(from, to, self.method));
            return;
        }
        let k2 = 2 * i64::from(self.k);
        let mid = self.at(k2 + 1);
        let next = self.at(k2 + 2);
        // Saturating: exact for a sine (|f| < 2^29); no panic for a wild closure.
        self.first = mid.saturating_sub(self.y);
        self.second = next.saturating_sub(mid);
        self.crossing = true;
    }

    fn climb(v: &mut i32) -> i8 {
        let s = super::sgn(i64::from(*v));
        *v -= i32::from(s);
        s
    }
}

impl<C: Curve> Interpolate for CurveTrace<C> {
    fn next_event(&mut self) -> Option<StepEvent> {
        if let Some(tail) = self.tail.as_mut() {
            return tail.next_event().map(|t| {
                // The tail was built in a frame where x grows with `dir`; flip back.
                let d = t.deltas();
                event_xy(d[X] * self.dir as i8, d[Y])
            });
        }
        let merge = self.method == Method::Dda;
        // Climb at this column, keeping the last step to merge with the crossing when
        // nothing is to be climbed after it.
        let keep_one = merge && self.second == 0 && self.first != 0;
        if self.first.abs() > i32::from(keep_one) {
            let s = Self::climb(&mut self.first);
            self.y += i32::from(s);
            return Some(event_xy(0, s));
        }
        if self.crossing {
            self.crossing = false;
            let mut sy = 0;
            if merge {
                if self.first != 0 {
                    sy = Self::climb(&mut self.first);
                } else if self.second != 0 {
                    sy = Self::climb(&mut self.second);
                }
            }
            self.y += i32::from(sy);
            self.k += 1;
            return Some(event_xy(self.dir as i8, sy));
        }
        if self.second != 0 {
            let s = Self::climb(&mut self.second);
            self.y += i32::from(s);
            return Some(event_xy(0, s));
        }
        self.plan_column();
        self.next_event()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn run(mut it: impl Interpolate, start: StepPos) -> Vec<StepPos> {
        let mut p = start;
        let mut v = std::vec![p];
        while let Some(t) = it.next_event() {
            t.apply(&mut p);
            v.push(p);
        }
        v
    }

    /// Does the curve pass through the square [p +- half]? Dense sampling over the
    /// square's x range (the curve is smooth at this scale).
    fn near_curve(f: &dyn Fn(f32) -> f32, u: f32, y: f32, half: f32) -> bool {
        let n = 16;
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        for i in 0..=n {
            let v = f(u - half + 2.0 * half * i as f32 / n as f32);
            lo = lo.min(v);
            hi = hi.max(v);
        }
        lo <= y + half + 1e-6 && hi >= y - half - 1e-6
    }

    proptest! {
        #[test]
        fn sine_trace_is_exact(amp in -2000.0f32..2000.0, omega in -0.3f32..0.3, phase in -7.0f32..7.0,
                               dx in -1500i32..1500, classic in any::<bool>()) {
            let s = Sine::new(amp, omega, phase).unwrap();
            let start = [17, -40, 3];
            let ideal_end = nearest(s.eval(dx as f32));
            let target = [17 + dx, -40 + ideal_end, 3];
            let method = if classic { Method::Classic } else { Method::Dda };
            let mut it = CurveTrace::new(start, target, s, method);
            let mut p = start;
            let f = |u: f32| s.eval(u);
            while let Some(t) = it.next_event() {
                if classic {
                    prop_assert_eq!(t.steps().count_ones(), 1);
                }
                t.apply(&mut p);
                let u = (p[0] - 17) as f32;
                prop_assert!(near_curve(&f, u, (p[1] + 40) as f32, 0.5), "{:?}", p);
            }
            prop_assert_eq!(p, target);
        }
    }

    #[test]
    fn sine_amplitude_is_limited_to_2_pow_28_steps() {
        assert_eq!(
            Sine::new(268_435_456.0, 0.001, 0.0).err(),
            Some(InterpError::TooLarge)
        );
        assert_eq!(
            Sine::new(-268_435_456.0, 0.001, 0.0).err(),
            Some(InterpError::TooLarge)
        );
        // Just below is accepted (rows up to 2^29 from the start fit the trace's
        // i32); a gentle one, so the trace stays short.
        let s = Sine::new(268_435_440.0, 1e-8, 1.0).unwrap();
        let start = [0, 0, 0];
        let target = [40, nearest(s.eval(40.0)), 0];
        let pts = run(CurveTrace::new(start, target, s, Method::Dda), start);
        assert_eq!(*pts.last().unwrap(), target);
    }

    #[test]
    fn arbitrary_function_reaches_an_off_curve_target_exactly() {
        let f = |u: f32| 0.001 * u * u;
        let start = [0, 0, 0];
        let pts = run(CurveTrace::new(start, [-100, 12, 0], f, Method::Dda), start);
        assert_eq!(*pts.last().unwrap(), [-100, 12, 0]);
        // y = 10 at x = -100 on the curve, then the tail climbs two more steps.
        assert!(pts.contains(&[-100, 10, 0]));
    }

    #[test]
    fn shallow_parts_step_diagonally_like_bresenham() {
        let f = |u: f32| 0.5 * u;
        let pts = run(CurveTrace::new([0; 3], [10, 5, 0], f, Method::Dda), [0; 3]);
        assert_eq!(pts.len() - 1, 10);
        let classic = run(
            CurveTrace::new([0; 3], [10, 5, 0], f, Method::Classic),
            [0; 3],
        );
        assert_eq!(classic.len() - 1, 15);
    }
}
