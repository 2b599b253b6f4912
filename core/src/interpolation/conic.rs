//! Ellipses and elliptical arcs (axis-aligned), traced on the implicit function
//! F(x, y) = A x^2 + B y^2 - C relative to the centre (A = b^2, B = a^2, C = a^2 b^2).
//! Circles have their own exact interpolator around any centre ([`super::circle`]).
//!
//! The feed direction at each point comes from the tangent (-B y, A x) (CCW) or its
//! negation (CW), which replaces the lab report's per-quadrant direction table and works
//! in every quadrant and across quadrant boundaries.
//! - DDA: the axis with the larger tangent component (the major axis) steps every
//!   step event; the other axis takes the integer nearest to the curve at the new major
//!   coordinate (a midpoint test on F), so per-axis error <= 0.5.
//! - Classic: one axis per step event; if F >= 0 (on or outside) take the candidate step that
//!   lowers F, otherwise the one that raises it. Within 1 step of the curve.
//!
//! The move ends when the trace reaches the target, or passes the ray from the centre
//! through the target (a full ellipse is target == start); if it passes the ray
//! without meeting the target, a short
//! straight tail goes to the integer target, so the end is exact even when rounding
//! put the target a step off the traced curve. A step event budget bounds every
//! trace, so hostile input cannot loop forever.

use super::line::Line;
use super::{event_xy, sgn, InterpError, Interpolate, Method, StepEvent};
use crate::motion::{StepPos, X, Y};

/// Largest |coordinate| relative to the centre and largest semi-axis, so that
/// A x^2 + B y^2 and C fit comfortably in i64 (2^15^4 = 2^60).
const ELLIPSE_LIMIT: i64 = 1 << 15;

/// A conic arc interpolator.
#[derive(Clone, Debug)]
pub struct Conic {
    a: i64,
    b: i64,
    c: i64,
    /// Current point relative to the centre.
    x: i64,
    y: i64,
    /// Target relative to the centre.
    tx: i64,
    ty: i64,
    ccw: bool,
    method: Method,
    budget: u64,
    /// Final straight piece to the exact target once the trace has arrived.
    tail: Option<Line>,
    /// On the last lap, the trace runs along the target ray.
    on_ray: bool,
    /// The point before the last step event (relative to the centre).
    prev: (i64, i64),
    finished: bool,
}

impl Conic {
    /// Elliptical arc with semi-axes `a` (X) and `b` (Y) around `start + center`.
    pub fn ellipse(
        start: StepPos,
        center: [i32; 2],
        a: i32,
        b: i32,
        target: StepPos,
        ccw: bool,
        method: Method,
    ) -> Result<Self, InterpError> {
        let (a, b) = (i64::from(a), i64::from(b));
        if a <= 0 || b <= 0 {
            return Err(InterpError::Degenerate);
        }
        if a > ELLIPSE_LIMIT || b > ELLIPSE_LIMIT {
            return Err(InterpError::TooLarge);
        }
        Self::build(
            start,
            center,
            target,
            b * b,
            a * a,
            a * a * b * b,
            ccw,
            method,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        start: StepPos,
        center: [i32; 2],
        target: StepPos,
        a: i64,
        b: i64,
        c: i64,
        ccw: bool,
        method: Method,
    ) -> Result<Self, InterpError> {
        let cx = i64::from(start[X]) + i64::from(center[0]);
        let cy = i64::from(start[Y]) + i64::from(center[1]);
        let (x, y) = (i64::from(start[X]) - cx, i64::from(start[Y]) - cy);
        let (tx, ty) = (i64::from(target[X]) - cx, i64::from(target[Y]) - cy);
        // Coordinates must stay small enough for the squared terms (any point of the
        // trace stays within the conic's bounding box, which this bounds too).
        for v in [x, y, tx, ty] {
            if v.abs() > 2 * ELLIPSE_LIMIT {
                return Err(InterpError::TooLarge);
            }
        }
        if tx == 0 && ty == 0 {
            return Err(InterpError::Degenerate);
        }
        // Budget: a generous multiple of the perimeter bound, per turn (f32: no 64-bit
        // division in the firmware).
        let r = crate::fmath::sqrt(c as f32 / a.min(b) as f32) as u64 + 2;
        let budget = 16 * r + 64;
        Ok(Conic {
            a,
            b,
            c,
            x,
            y,
            tx,
            ty,
            ccw,
            method,
            budget,
            tail: None,
            on_ray: false,
            prev: (x, y),
            finished: false,
        })
    }

    /// Feed direction at the present point (step space, not normalised).
    pub fn direction(&self) -> [f32; 2] {
        let (tx, ty) = self.tangent(self.x, self.y);
        [tx as f32, ty as f32]
    }

    /// Ideal path length of the last step event in mm (`spx`, `spy`: steps per mm): the
    /// change of the parameter angle t (x = a cos t, y = b sin t) between the two points,
    /// atan(cross/dot) ~ cross/dot for one step, times |dP/dt| at their midpoint. The
    /// angles telescope, so the lengths of a whole arc add up to its true length.
    pub fn last_tick_len(&self, spx: f32, spy: f32) -> f32 {
        let (x1, y1) = self.prev;
        let (x2, y2) = (self.x, self.y);
        // Steps (-1..=1), the cross product of neighbours (|x| + |y|) and sums of two
        // coordinates fit i32 (every point is within 2^29.5 + 1 of the centre, see
        // [`Conic::build`]): converted as i32, the same f32 as from i64, without the
        // 64-bit conversion routine's argument pair.
        let f = |v: i64| v as i32 as f32;
        if self.tail.is_some() {
            let (dx, dy) = (f(x2 - x1) / spx, f(y2 - y1) / spy);
            return crate::fmath::sqrt(dx * dx + dy * dy);
        }
        let (a, b) = (self.a as f32, self.b as f32);
        let cross = f(x1 * y2 - x2 * y1);
        let dot = a * (x1 * x2) as f32 + b * (y1 * y2) as f32;
        if dot <= 0.0 {
            return 0.0;
        }
        // One step turns the radius by about 1/R: atan(x) = x - x^3/3 differs by
        // < 1e-9 relative for any radius of more than a few steps.
        let dt = cross.abs() * crate::fmath::sqrt(a * b) / dot;
        let (mx, my) = (f(x1 + x2) * 0.5, f(y1 + y2) * 0.5);
        let vx = crate::fmath::sqrt(b / a) * my / spx;
        let vy = crate::fmath::sqrt(a / b) * mx / spy;
        dt * crate::fmath::sqrt(vx * vx + vy * vy)
    }

    fn f(&self, x: i64, y: i64) -> i64 {
        self.a * x * x + self.b * y * y - self.c
    }

    /// Tangent direction (not normalised) at (x, y) in the feed direction.
    fn tangent(&self, x: i64, y: i64) -> (i64, i64) {
        let (tx, ty) = (-self.b * y, self.a * x);
        if self.ccw {
            (tx, ty)
        } else {
            (-tx, -ty)
        }
    }

    /// Signed position of `(x, y)` relative to the target ray: the cross product
    /// target x p, oriented so that it grows in the feed direction. i64 is enough:
    /// every coordinate is within 2^30.5 of the centre (the limits checked in
    /// [`Conic::build`]), so each product is below 2^61.
    fn side(&self, x: i64, y: i64) -> i64 {
        let cr = self.tx * y - self.ty * x;
        if self.ccw {
            cr
        } else {
            -cr
        }
    }

    fn ahead(&self, x: i64, y: i64) -> bool {
        self.tx * x + self.ty * y > 0
    }

    /// Nearest integer to the curve along the minor axis at major coordinate `m`,
    /// starting the search from `near` (same sign branch). `x_major` says which axis
    /// `m` belongs to; `branch` picks the side when `near` is 0 (the sign of the
    /// tangent's minor component).
    fn nearest_minor(&self, x_major: bool, m: i64, near: i64, branch: i64) -> i64 {
        let (ca, cb) = if x_major {
            (self.a, self.b)
        } else {
            (self.b, self.a)
        };
        // 4 F at (m, (2u + s)/2) = 4 ca m^2 + cb (2u + s)^2 - 4 C, increasing in u >= 0.
        let g = |u2: i64| 4 * ca * m * m + cb * u2 * u2 - 4 * self.c;
        let sign = if near < 0 || (near == 0 && branch < 0) {
            -1
        } else {
            1
        };
        let mut u = near.abs();
        for _ in 0..4 {
            if g(2 * u + 1) <= 0 {
                u += 1;
            } else {
                break;
            }
        }
        for _ in 0..4 {
            if u > 0 && g(2 * u - 1) > 0 {
                u -= 1;
            } else {
                break;
            }
        }
        sign * u
    }

    fn dda_candidate(&self) -> (i64, i64) {
        let (tx, ty) = self.tangent(self.x, self.y);
        let x_first = tx.abs() >= ty.abs();
        // A candidate must keep its major coordinate within the conic's extent (there
        // is then a curve point at that coordinate, and the nearest minor integer is
        // within 0.5 of it). Near a sharp vertex of a thin ellipse the tangent is
        // steep while the curve ends within a step: stepping the "major" axis past the
        // vertex would leave no such point, so the other axis goes first there.
        // One body for both orders: (major, minor) coordinates, tangent components
        // and the major axis' coefficient, swapped back on return.
        for x_major in [x_first, !x_first] {
            let (m, n, tm, tn, ca) = if x_major {
                (self.x, self.y, tx, ty, self.a)
            } else {
                (self.y, self.x, ty, tx, self.b)
            };
            let s = if tm != 0 { sgn(tm) } else { -sgn(m) };
            let nm = m + i64::from(s);
            let nn = self.nearest_minor(x_major, nm, n, tn);
            if (nn - n).abs() <= 1 && ca * nm * nm <= self.c {
                return if x_major { (nm, nn) } else { (nn, nm) };
            }
        }
        // Not reachable for a well-formed conic; move along the tangent to stay safe.
        (self.x + i64::from(sgn(tx)), self.y + i64::from(sgn(ty)))
    }

    fn classic_candidate(&self) -> (i64, i64) {
        let (tx, ty) = self.tangent(self.x, self.y);
        // On an axis the feed is along one axis only: a step across it would make no
        // progress and can end a whole step off a circle whose radius is not an integer.
        if tx == 0 && ty != 0 {
            return (self.x, self.y + i64::from(sgn(ty)));
        }
        if ty == 0 && tx != 0 {
            return (self.x + i64::from(sgn(tx)), self.y);
        }
        let sx = if tx != 0 { sgn(tx) } else { -sgn(self.x) };
        let sy = if ty != 0 { sgn(ty) } else { -sgn(self.y) };
        let c1 = (self.x + i64::from(sx), self.y);
        let c2 = (self.x, self.y + i64::from(sy));
        let (f1, f2) = (self.f(c1.0, c1.1), self.f(c2.0, c2.1));
        let inward_first = f1 <= f2;
        if (self.f(self.x, self.y) >= 0) == inward_first {
            c1
        } else {
            c2
        }
    }

    /// Moves to the neighbouring point `p`: the step event that gets there.
    fn go(&mut self, p: (i64, i64)) -> StepEvent {
        let t = event_xy(sgn(p.0 - self.x), sgn(p.1 - self.y));
        self.prev = (self.x, self.y);
        (self.x, self.y) = p;
        t
    }

    /// Switches to the straight tail from the present point to the target.
    fn start_tail(&mut self) {
        let from = [self.x as i32, self.y as i32, 0];
        let to = [self.tx as i32, self.ty as i32, 0];
        self.tail = Some(Line::new(from, to, self.method));
    }

    /// The next point of the trace, or `None` when the tail must take over.
    fn trace(&mut self) -> Option<(i64, i64)> {
        if self.budget == 0 {
            return None;
        }
        self.budget -= 1;
        let (nx, ny) = match self.method {
            Method::Dda => self.dda_candidate(),
            Method::Classic => self.classic_candidate(),
        };
        // Does this step event reach or pass the target ray on the last lap?
        let before = self.side(self.x, self.y);
        let after = self.side(nx, ny);
        if (nx, ny) == (self.tx, self.ty) {
            self.finished = true;
        } else if self.on_ray {
            // Tracing along the ray (a flat stretch): leave for the target once the
            // trace turns away from it.
            if after != 0 || !self.ahead(nx, ny) {
                return None;
            }
        } else if before < 0 && after >= 0 && self.ahead(nx, ny) {
            if after > 0 {
                return None;
            } else {
                self.on_ray = true;
            }
        }
        Some((nx, ny))
    }
}

impl Interpolate for Conic {
    fn next_event(&mut self) -> Option<StepEvent> {
        if self.finished {
            return None;
        }
        if self.tail.is_none() {
            if let Some(p) = self.trace() {
                return Some(self.go(p));
            }
            self.start_tail();
        }
        // The tail's step events are XY steps: the point follows them like the trace's.
        let Some(t) = self.tail.as_mut().and_then(|t| t.next_event()) else {
            self.finished = true;
            return None;
        };
        let d = t.deltas();
        Some(self.go((self.x + i64::from(d[X]), self.y + i64::from(d[Y]))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn run(mut c: Conic, start: StepPos) -> Vec<StepPos> {
        let mut p = start;
        let mut v = std::vec![p];
        while let Some(t) = c.next_event() {
            t.apply(&mut p);
            v.push(p);
            assert!(v.len() < 10_000_000);
        }
        v
    }

    /// Does the unit-free square [p +- 0.5] (relative to the centre) meet the conic
    /// A x^2 + B y^2 = C? F is convex: min at the clamped origin, max at a corner.
    fn cell_meets(a: f64, b: f64, c: f64, x: f64, y: f64, half: f64) -> bool {
        let f = |x: f64, y: f64| a * x * x + b * y * y - c;
        let clamp = |v: f64| {
            if v - half > 0.0 {
                v - half
            } else if v + half < 0.0 {
                v + half
            } else {
                0.0
            }
        };
        let fmin = f(clamp(x), clamp(y));
        let fmax = [(-half, -half), (-half, half), (half, -half), (half, half)]
            .iter()
            .map(|&(dx, dy)| f(x + dx, y + dy))
            .fold(f64::MIN, f64::max);
        fmin <= 0.0 && fmax >= 0.0
    }

    #[test]
    fn rejects_degenerate_and_oversized_input() {
        assert_eq!(
            Conic::ellipse([0; 3], [-70000, 0], 70000, 10, [0; 3], true, Method::Dda).err(),
            Some(InterpError::TooLarge)
        );
        assert_eq!(
            Conic::ellipse([0; 3], [-5, 0], 5, 0, [0; 3], true, Method::Dda).err(),
            Some(InterpError::Degenerate)
        );
    }

    #[test]
    fn dda_thin_ellipse_does_not_step_past_its_vertex() {
        // Found by the property test below: a = 41, b = 1682, from the rounded point
        // at 1.5585 rad counter-clockwise to angle 0. The start (1, 1682) lies half a
        // step outside, where the tangent is at 45 degrees; stepping Y first went to
        // (0, 1683), a whole step off the curve.
        let (a, b) = (41i32, 1682i32);
        let start = [1, 1682, 0];
        let target = [41, 0, 0];
        let pts = run(
            Conic::ellipse(start, [-1, -1682], a, b, target, true, Method::Dda).unwrap(),
            start,
        );
        assert_eq!(*pts.last().unwrap(), target);
        let (af, bf) = (f64::from(a), f64::from(b));
        for p in &pts {
            assert!(
                cell_meets(
                    bf * bf,
                    af * af,
                    af * af * bf * bf,
                    f64::from(p[0]),
                    f64::from(p[1]),
                    0.5 + 1e-9
                ),
                "{p:?}"
            );
        }
    }

    proptest! {
        #[test]
                #[test]
                #[test]
        fn dda_ellipses_stay_within_half_a_step_per_axis(a in 1i32..4000, b in 1i32..4000, t0 in 0.0f64..std::f64::consts::TAU, t1 in 0.0f64..std::f64::consts::TAU, ccw in any::<bool>(), classic in any::<bool>()) {
            let (af, bf) = (f64::from(a), f64::from(b));
            // Start: the ideal point at angle t0, rounded; centre at the origin.
            let sx = (af * t0.cos()).round() as i32;
            let sy = (bf * t0.sin()).round() as i32;
            let start = [sx, sy, 0];
            let target = [(af * t1.cos()).round() as i32, (bf * t1.sin()).round() as i32, 0];
            prop_assume!(target != [0, 0, 0]);
            let method = if classic { Method::Classic } else { Method::Dda };
            let pts = run(Conic::ellipse(start, [-sx, -sy], a, b, target, ccw, method).unwrap(), start);
            prop_assert_eq!(*pts.last().unwrap(), target);
            let half = if classic { 1.0 } else { 0.5 + 1e-9 };
            for p in &pts {
                prop_assert!(cell_meets(bf * bf, af * af, af * af * bf * bf, f64::from(p[0]), f64::from(p[1]), half), "{:?}", p);
            }
        }
    }
}
