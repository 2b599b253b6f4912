//! Circles and circular arcs around any centre, exact in integer step space: the centre
//! and the radius are kept in 1/256 step, so an arc whose centre or start is between
//! steps (G-code I/J in mm, the R form, inch units) is traced on its own circle, not on
//! one through rounded points.
//!
//! Everything is relative to the centre in 1/256 step (`X = 256 x - CX`), and the
//! implicit function F = X^2 + Y^2 - R^2 is kept as an exact i64 that every step updates
//! with two additions (midpoint recurrences: a step of an axis in its direction adds
//! `e = 2 s X + s^2`, s = +-256, and then `e` grows by 2 s^2).
//!
//! - DDA ([`Method::Dda`]): the circle is cut into octant pieces. In a piece one axis
//!   (the major) steps on every step event and the other (the minor) takes the grid point
//!   nearest the circle at the new major coordinate, one midpoint test: per-axis error
//!   <= 0.5 step, so every position is within 0.5 step of the circle. A piece runs
//!   either toward the minor axis (|major| falls to the grid line nearest the centre's
//!   line, the minor moves outward) or away from it (|major| grows up to the diagonal,
//!   the minor moves inward), so every piece's step event count is known when it begins and
//!   the path position is a smooth function of the major coordinate ([`Circle::path_ahead`]):
//!   the segment preparation times a whole piece with a few polynomials.
//! - Classic ([`Method::Classic`], the lab report's point-by-point comparison, 3.6):
//!   one axis per step event, F >= 0 steps the axis that moves inward, F < 0 the one that
//!   moves outward, within a quadrant whose feed directions are fixed; within 1 step of
//!   the circle (plus at most 1/(2R) where the inward axis crosses the centre's line
//!   between two grid lines). Each step event is timed on its own (it is the teaching mode).
//!
//! The arc ends at the integer target: the trace stops where it reaches the target's
//! coordinate on the last lap (the piece that contains it), and a straight tail of
//! usually no more than one step goes to the target, which rounding may have put a step
//! off the traced points. Full circles are `target == start`; `turns` adds revolutions.

use super::line::Line;
use super::{event_xy, InterpError, Interpolate, Method, Next, StepEvent};
use crate::motion::{StepPos, X, Y};

/// Largest |coordinate| relative to the centre, 1/256 step (2^22 steps, 52 m at 80
/// steps/mm): squares and their sums stay below 2^62.
pub const LIMIT: i64 = 1 << 30;
/// One step in the fixed-point unit.
const ONE: i32 = 256;
/// What a step adds to the increment `e` of its axis: 2 s^2.
const E_GROWTH: i64 = 2 * 256 * 256;

/// The circle is traced by octant pieces (DDA) or quadrant pieces (classic).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Piece {
    /// Major axis (DDA) or the axis moving inward (classic): 0 = X, 1 = Y.
    major: usize,
    /// DDA: the minor moves toward the centre's line (the piece runs away from the
    /// minor axis up to the diagonal).
    inward: bool,
    /// DDA: step events left in the piece. Classic: unused.
    left: u32,
    /// This is the last piece: it ends at the target's coordinate.
    last: bool,
}

/// The leg of the arc being stepped: settling onto the circle, tracing it, the
/// straight tail to the target, done.
#[derive(Clone, Debug)]
enum Leg {
    /// Minor-only steps onto the grid point nearest the circle before the first DDA
    /// piece (the rounded start can be up to a step off it; signed count).
    Settle(i32),
    Trace,
    /// The straight tail to the integer target (relative coordinates, whole steps).
    Tail(Line),
    Done,
}

/// A circular arc interpolator.
#[derive(Clone, Debug)]
pub struct Circle {
    /// Present point relative to the centre, 1/256 step.
    p: [i32; 2],
    /// X^2 + Y^2 - R^2 at the present point.
    f: i64,
    /// Per axis: what a step in its present direction adds to F.
    e: [i64; 2],
    /// Per axis: its present direction, +-256.
    dir: [i32; 2],
    r2: i64,
    /// Radius, steps (f32: path positions and their bounds only).
    radius: f32,
    /// floor(sqrt(R^2 / 2)): the largest |major| of a DDA octant piece.
    diag: i32,
    ccw: bool,
    method: Method,
    piece: Piece,
    /// Pieces begun (octants for DDA, quadrants for classic).
    pieces: u32,
    /// Passes of the target still to make before it ends the arc (whole turns).
    skip: u32,
    /// The last piece reached the target's coordinate at its very end (the next piece
    /// begins there: the same pass, not another).
    hit_at_end: bool,
    /// The trace has made a step since the start: before it has, a piece that begins
    /// at the start (after an empty first piece) does not count the start as a pass.
    moved: bool,
    /// Longest the trace may run, in pieces (an arc whose target is off the circle
    /// still ends: the tail takes it there).
    max_pieces: u32,
    /// Target relative to the centre, 1/256 step.
    target: [i32; 2],
    leg: Leg,
    /// The point before the last step event (classic and tail step events: their length).
    prev: [i32; 2],
    /// See [`Circle::entry_shift`].
    entry: f32,
    /// The major coordinate where the last [`Circle::path_ahead`] ended and the
    /// circle's minor there (the next call usually begins there).
    last_end: core::cell::Cell<(usize, i32, f32)>,
}

/// Sign of v as -1, 0 or 1.
fn sgn(v: i32) -> i32 {
    i32::from(v > 0) - i32::from(v < 0)
}

/// |atan2(cross, dot)| for the angle (at most 45 degrees: one piece) between two points
/// of the circle: above tan = 0.2 halved (tan(a/2) = t / (1 + sqrt(1 + t^2))) until
/// below, then the series to t^11, whose error (< 1e-10) is far below the general
/// arctangent's 3e-7 rad (which, over a long arc, would shift a step's position by a
/// thousandth of a step and its time near a stop by microseconds).
#[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN takes the general arctangent
fn small_angle(cross: f32, dot: f32) -> f32 {
    if !(dot > 0.0) {
        return crate::fmath::abs(crate::fmath::atan2(cross, dot));
    }
    let mut x = crate::fmath::abs(cross) / dot;
    let mut scale = 1.0;
    while x > 0.2 {
        x /= 1.0 + crate::fmath::sqrt(1.0 + x * x);
        scale *= 2.0;
    }
    let z = x * x;
    let series =
        1.0 - z * (1.0 / 3.0 - z * (0.2 - z * (1.0 / 7.0 - z * (1.0 / 9.0 - z * (1.0 / 11.0)))));
    scale * x * series
}

impl Circle {
    /// Arc from the integer `start` to the integer `target`, on the circle around
    /// `center` through `from` (both absolute, 1/256 step, i64 so that a whole-step
    /// centre anywhere in the step range fits; `from` is the exact start, which `start`
    /// rounds). `turns` extra revolutions; `target == start` is a full
    /// circle.
    #[inline(always)]
    pub fn new(
        start: StepPos,
        from: [i64; 2],
        center: [i64; 2],
        target: StepPos,
        ccw: bool,
        turns: u16,
        method: Method,
    ) -> Result<Self, InterpError> {
        let rel = |v: i32, c: i64| (i64::from(v) * i64::from(ONE)).wrapping_sub(c);
        let exact = [
            from[0].wrapping_sub(center[0]),
            from[1].wrapping_sub(center[1]),
        ];
        let p = [rel(start[X], center[0]), rel(start[Y], center[1])];
        let t = [rel(target[X], center[0]), rel(target[Y], center[1])];
        if exact.iter().chain(&p).chain(&t).any(|v| v.abs() > LIMIT) {
            return Err(InterpError::TooLarge);
        }
        let r2 = exact[0] * exact[0] + exact[1] * exact[1];
        if r2 == 0 {
            return Err(InterpError::Degenerate);
        }
        let radius = crate::fmath::sqrt(r2 as f32) / ONE as f32;
        let mut c = Circle {
            p: [p[0] as i32, p[1] as i32],
            f: 0,
            e: [0; 2],
            dir: [0; 2],
            r2,
            radius,
            diag: crate::fmath::isqrt((r2 >> 1) as u64) as i32,
            ccw,
            method,
            piece: Piece {
                major: 0,
                inward: false,
                left: 0,
                last: false,
            },
            pieces: 0,
            skip: u32::from(turns),
            hit_at_end: false,
            moved: false,
            max_pieces: 0,
            target: [t[0] as i32, t[1] as i32],
            leg: Leg::Trace,
            prev: [0; 2],
            entry: 0.0,
            last_end: core::cell::Cell::new((2, 0, 0.0)),
        };
        c.f = c.value(c.p);
        let per_turn = match method {
            Method::Dda => 8,
            Method::Classic => 4,
        };
        // The arc ends at the target's pass after `turns` whole turns. A piece begins
        // where the one before ended, so the start's own piece counts a target only
        // strictly ahead: a full circle (or one behind the start) is met a lap later.
        c.max_pieces = per_turn * (u32::from(turns) + 1) + 2;
        if r2 < i64::from(ONE) * i64::from(ONE) {
            // A circle inside one grid cell: the target is all there is to reach.
            c.start_tail();
            return Ok(c);
        }
        c.begin_piece();
        c.pass_target(1);
        Ok(c)
    }

    /// Radius in steps.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    fn value(&self, p: [i32; 2]) -> i64 {
        let (x, y) = (i64::from(p[0]), i64::from(p[1]));
        x * x + y * y - self.r2
    }

    /// Tangent direction (feed direction) at `p`, signs only: (-Y, X) counter-clockwise.
    fn tangent(&self, p: [i32; 2]) -> [i32; 2] {
        let t = [-sgn(p[1]), sgn(p[0])];
        if self.ccw {
            t
        } else {
            [-t[0], -t[1]]
        }
    }

    /// Points the axis directions along the feed at the present point and sets their
    /// increments.
    fn set_dirs(&mut self, d: [i32; 2]) {
        for (i, d) in d.into_iter().enumerate() {
            self.dir[i] = d * ONE;
            let s = i64::from(self.dir[i]);
            self.e[i] = 2 * s * i64::from(self.p[i]) + s * s;
        }
    }

    /// Starts the next piece: the one the present point belongs to at the start, then
    /// each piece's successor.
    fn begin_piece(&mut self) {
        self.pieces += 1;
        match self.method {
            Method::Dda if self.pieces == 1 => self.begin_first_octant(),
            Method::Dda => {
                let (major, toward) = if self.piece.inward {
                    // Away from the minor's axis up to the diagonal: the minor takes
                    // over as the major, moving toward its own axis. The directions
                    // stay as they are.
                    (1 - self.piece.major, true)
                } else {
                    // The major crossed its axis line: the minor turns inward.
                    let n = 1 - self.piece.major;
                    let mut d = [sgn(self.dir[0]), sgn(self.dir[1])];
                    d[n] = -sgn(self.p[n]);
                    self.set_dirs(d);
                    (self.piece.major, false)
                };
                self.begin_octant(major, toward);
            }
            Method::Classic => self.begin_quadrant(),
        }
        if self.method == Method::Dda && self.pieces == 1 {
            // Only the rounded start can be off its nearest point: where a piece ends,
            // the point was the nearest along the old major, which the new piece's
            // one-sided test continues from.
            let catch = self.to_nearest_minor();
            if catch != 0 {
                self.leg = Leg::Settle(catch);
            }
        }
    }

    /// Minor steps (signed) from the present point to the grid point nearest the circle
    /// at the present major coordinate: 0 unless the rounded start is off it.
    fn to_nearest_minor(&self) -> i32 {
        let (m, n) = (self.piece.major, 1 - self.piece.major);
        let f0 = self.f;
        let pm = i64::from(self.p[m]);
        if f0 == 0 || pm * pm >= self.r2 {
            // On the circle, or beyond its extent along the major (a start rounded
            // outward): the first step event moves the major back in.
            return 0;
        }
        // Toward the circle along the minor: inward when outside.
        let out = if self.p[n] < 0 { -1 } else { 1 };
        let sigma = if f0 > 0 { -out } else { out };
        let mut q = self.p;
        let mut j = 0;
        while j < 4 {
            q[n] = self.p[n] + (j * ONE + ONE / 2) * sigma;
            // Still on the start's side of the circle at the midpoint: one more step.
            if (self.value(q) > 0) != (f0 > 0) || self.value(q) == 0 {
                break;
            }
            j += 1;
        }
        j * sigma
    }

    /// One minor-only step of the settle leg.
    fn settle_tick(&mut self, sigma: i32) -> StepEvent {
        let n = 1 - self.piece.major;
        self.prev = self.p;
        self.p[n] += sigma * ONE;
        self.f = self.value(self.p);
        // Keep the increments in step with the moved minor.
        let d = [sgn(self.dir[0]), sgn(self.dir[1])];
        self.set_dirs(d);
        let mut dl = [0i8; 2];
        dl[n] = sigma as i8;
        event_xy(dl[0], dl[1])
    }

    /// DDA: the octant piece the start point belongs to. The major is the axis with the
    /// smaller |coordinate| (the circle is flatter than 45 degrees along it).
    fn begin_first_octant(&mut self) {
        let p = self.p;
        let major = if p[0].unsigned_abs() <= p[1].unsigned_abs() {
            0
        } else {
            1
        };
        let minor = 1 - major;
        let t = self.tangent(p);
        // On the minor's axis line the tangent is along the major: it moves on away.
        let sm = if t[major] != 0 { t[major] } else { 1 };
        let toward = sm * sgn(p[major]) < 0;
        let mut d = [0; 2];
        d[major] = sm;
        d[minor] = sgn(p[minor]) * if toward { 1 } else { -1 };
        self.set_dirs(d);
        self.begin_octant(major, toward);
    }

    /// DDA: an octant piece with the present directions. Toward the minor's axis it runs
    /// while |major| falls (k < (|major| + 128) / 256); away from it while |major| <= diag.
    fn begin_octant(&mut self, major: usize, toward: bool) {
        let m = i64::from(self.p[major]);
        let left = if toward {
            (m.abs() + 127) >> 8
        } else {
            let room = i64::from(self.diag) - m * i64::from(sgn(self.dir[major]));
            if room < 0 {
                0
            } else {
                room >> 8
            }
        };
        self.piece = Piece {
            major,
            inward: !toward,
            left: left.min(i64::from(u32::MAX)) as u32,
            last: false,
        };
    }

    /// Classic: the quadrant piece at the present point (a zero coordinate belongs to
    /// the quadrant the feed enters).
    fn begin_quadrant(&mut self) {
        let p = self.p;
        let mut t = self.tangent(p);
        // On an axis the tangent is along the other axis only: that one moves, the
        // other takes the direction it will have just after.
        for i in 0..2 {
            if t[i] == 0 {
                let o = 1 - i;
                // The coordinate that is zero moves with t[o]; after that step the
                // other's direction follows the new sign.
                let mut q = p;
                q[o] += t[o] * ONE;
                t[i] = self.tangent(q)[i];
            }
        }
        self.set_dirs(t);
        // The axis moving inward: its |coordinate| falls.
        let major = if i64::from(t[0]) * i64::from(p[0]) < 0 {
            0
        } else {
            1
        };
        self.piece = Piece {
            major,
            inward: true,
            left: u32::MAX,
            last: false,
        };
    }

    /// Step events from the present point to the target's coordinate if the present piece
    /// reaches it (0 = here); the target must lie on the piece's side of the centre.
    fn target_in_piece(&self) -> Option<u32> {
        let (p, t) = (self.p, self.target);
        let m = self.piece.major;
        let ahead = |i: usize| (i64::from(t[i]) - i64::from(p[i])) * i64::from(sgn(self.dir[i]));
        match self.method {
            Method::Dda => {
                let n = 1 - m;
                // The side of the centre the piece runs on: its minor's, or, within a
                // step of the axis (only a circle a few steps across starts a piece
                // there), the side its minor moves to.
                let side = if p[n].abs() < ONE {
                    sgn(self.dir[n])
                } else {
                    sgn(p[n])
                };
                if sgn(t[n]) != side && sgn(t[n]) != 0 {
                    return None;
                }
                let k = ahead(m);
                // At the present major coordinate (k = 0) the target must be the present
                // point or a minor step ahead of it, not one the trace just left.
                let here = k != 0 || (ahead(n) >= 0 && ahead(n) <= i64::from(ONE));
                (here && k >= 0 && k % 256 == 0 && k / 256 <= i64::from(self.piece.left))
                    .then_some((k / 256) as u32)
            }
            Method::Classic => {
                // Both coordinates move monotonically in a quadrant: the target is ahead
                // if neither is behind and it is in this quadrant.
                let same_quadrant =
                    (0..2).all(|i| sgn(t[i]) == sgn(p[i]) || sgn(t[i]) == 0 || sgn(p[i]) == 0);
                let (a0, a1) = (ahead(0), ahead(1));
                (same_quadrant && a0 >= 0 && a1 >= 0).then_some(((a0 + a1) / 256) as u32)
            }
        }
    }

    /// Counts a pass of the target in the piece just begun (at least `k_min` step events
    /// ahead); the pass after the whole turns makes this the last piece.
    fn pass_target(&mut self, k_min: u32) {
        let hit = self.target_in_piece().filter(|&k| k >= k_min);
        let counts = match hit {
            // Here: not the start itself before the trace has moved (a full circle
            // after an empty first piece), nor the pass the last piece ended on.
            Some(0) => !self.hit_at_end && self.moved,
            Some(_) => true,
            None => false,
        };
        self.hit_at_end =
            self.method == Method::Dda && hit == Some(self.piece.left) && hit.is_some();
        if counts {
            if self.skip == 0 {
                self.piece.last = true;
                self.cut_at_target();
            } else {
                self.skip -= 1;
            }
        }
    }

    /// The last piece ends at the target's major coordinate (DDA).
    fn cut_at_target(&mut self) {
        if self.method == Method::Dda {
            let m = self.piece.major;
            let k = (i64::from(self.target[m]) - i64::from(self.p[m]))
                * i64::from(sgn(self.dir[m]))
                / 256;
            self.piece.left = k.max(0).min(i64::from(self.piece.left)) as u32;
        }
    }

    /// The present piece is used up: the next one, or the tail.
    fn next_piece(&mut self) {
        if self.piece.last || self.pieces >= self.max_pieces {
            self.start_tail();
            return;
        }
        let old = self.piece.major;
        self.begin_piece();
        self.pass_target(0);
        self.entry = if self.piece.major == old {
            0.0
        } else {
            self.param_shift(old)
        };
    }

    /// Where the present point is along the circle by the new major's coordinate, less
    /// where it was by the old one's (`old`), steps along the feed: a grid point off
    /// the circle has a different nearest... point by each coordinate, so a piece of the
    /// other axis begins a little ahead of (or behind) where the last one ended.
    fn param_shift(&self, old: usize) -> f32 {
        let r = self.radius;
        let s = 1.0 / ONE as f32;
        let ideal = |major: usize| {
            let n = 1 - major;
            let m = self.p[major] as f32 * s;
            let side = if self.p[n] < 0 { -1.0 } else { 1.0 };
            let mut q = [0.0f32; 2];
            q[major] = m;
            q[n] = side * crate::fmath::sqrt((r * r - m * m).max(0.0));
            q
        };
        let (a, b) = (ideal(old), ideal(1 - old));
        let angle = crate::fmath::atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1]);
        if self.ccw {
            r * angle
        } else {
            -r * angle
        }
    }

    /// Path position of the present run's start less the end of the run before it,
    /// steps (see `Circle::param_shift`; 0 unless the major axis changed).
    pub fn entry_shift(&self) -> f32 {
        self.entry
    }

    fn start_tail(&mut self) {
        // The present point and the target differ by whole steps (same grid).
        let d = [
            (self.target[0] - self.p[0]) / ONE,
            (self.target[1] - self.p[1]) / ONE,
        ];
        self.leg = Leg::Tail(Line::new([0; 3], [d[0], d[1], 0], self.method));
    }

    /// What comes next (moving on to the next piece when this one is used up): a DDA
    /// piece is a run; a classic step event is timed on its own; settle and tail steps are
    /// extra steps. (Not an iterator: it never ends, it says `Done`.)
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Next {
        loop {
            match (&self.leg, self.method) {
                (Leg::Done, _) => return Next::Done,
                (Leg::Settle(_), _) => return Next::Extra,
                // A tail step has a length (straight, [`Circle::last_tick_len`]): it is
                // timed along the profile like a trace step event. A tail can be many steps (a
                // classic trace stops where the next step event would pass the target's
                // coordinate, e.g. along a near-vertical stretch), and timed as
                // catch-up steps they would come at ever shorter intervals.
                (Leg::Tail(_), _) => return Next::StepEvent,
                (Leg::Trace, Method::Dda) if self.piece.left == 0 => self.next_piece(),
                (Leg::Trace, Method::Dda) => return Next::Run(self.piece.left),
                (Leg::Trace, Method::Classic) => return Next::StepEvent,
            }
        }
    }

    /// Largest |d^n s / dk^n| (n = 1..4) over the next `k` step events of a DDA piece, s the
    /// path in steps and k the major coordinate: s = R asin(u), u = k / R, whose
    /// derivatives grow with |u| (at most 1/sqrt 2 in a piece). Bounded without roots:
    /// 1/(1-u^2), u/(1-u^2)^2, (1+2u^2)/(1-u^2)^3 and (9u+6u^3)/(1-u^2)^4, over R^n.
    pub fn run_bounds(&self, k: u32) -> [f32; 4] {
        let m = self.piece.major;
        let r = self.radius.max(1.0);
        let m0 = self.p[m] as f32 / ONE as f32;
        let m1 = m0 + k as f32 * sgn(self.dir[m]) as f32;
        let u = (crate::fmath::abs(m0).max(crate::fmath::abs(m1)) / r).min(0.7072);
        let u2 = u * u;
        let c = 1.0 / (1.0 - u2);
        let ir = 1.0 / r;
        [
            c,
            u * c * c * ir,
            (1.0 + 2.0 * u2) * c * c * c * ir * ir,
            (9.0 + 6.0 * u2) * u * (c * c) * (c * c) * ir * ir * ir,
        ]
    }

    /// The present run is the arc's last (it ends at the target's coordinate).
    pub fn in_last_piece(&self) -> bool {
        self.piece.last && matches!(self.leg, Leg::Trace)
    }

    /// The major axis of the present piece (0 = X): which coordinate a run's path
    /// position follows.
    pub fn major(&self) -> usize {
        self.piece.major
    }

    /// Path position `k` step events ahead in the present DDA piece (k <= its run),
    /// relative to the present point, in steps along the circle, and its rate in steps
    /// per step event there. The position of a step event is the point of the circle at its major
    /// coordinate.
    pub fn path_ahead(&self, k: u32) -> (f32, f32) {
        let m = self.piece.major;
        let n = 1 - m;
        let r = self.radius;
        let s = 1.0 / ONE as f32;
        let m0 = self.p[m] as f32 * s;
        let m1 = m0 + (k as f32) * sgn(self.dir[m]) as f32;
        let side = if self.p[n] < 0 { -1.0 } else { 1.0 };
        let minor = |mm: f32| side * crate::fmath::sqrt((r * r - mm * mm).max(0.0));
        // The circle's minor at the present major: from the last call when it ended here.
        let (cached_axis, cached_m, cached_n) = self.last_end.get();
        let n0 = if (cached_axis, cached_m) == (m, self.p[m]) {
            cached_n
        } else {
            minor(m0)
        };
        let n1 = minor(m1);
        self.last_end
            .set((m, self.p[m] + k as i32 * self.dir[m], n1));
        // Angle between the two circle points (small: one piece is an octant). The
        // cross product from the differences, without cancellation: dm is k, and
        // dn = n1 - n0 = (m0 - m1)(m0 + m1) / (n0 + n1) on the circle.
        let dm = m1 - m0;
        let dn = if n0 + n1 != 0.0 {
            -dm * (m0 + m1) / (n0 + n1)
        } else {
            n1 - n0
        };
        let cross = m0 * dn - n0 * dm;
        let dot = m0 * m1 + n0 * n1;
        let angle = small_angle(cross, dot);
        // (Never 0: a piece stays within a step of the diagonal, |minor| >= ~R / sqrt 2.)
        let rate = r / crate::fmath::abs(n1).max(r * 0.5);
        (r * angle, rate)
    }

    /// DDA step events of the present piece, at most `out.len()`; the count written.
    fn dda_ticks(&mut self, out: &mut [StepEvent]) -> usize {
        let m = self.piece.major;
        let n = 1 - m;
        let count = out.len().min(self.piece.left as usize);
        let (mut pm, mut pn) = (self.p[m], self.p[n]);
        let (mut em, mut en, mut f) = (self.e[m], self.e[n], self.f);
        let (sm, sn) = (self.dir[m], self.dir[n]);
        let inward = self.piece.inward;
        let mut d = [0i8; 2];
        d[m] = sgn(sm) as i8;
        let straight = event_xy(d[0], d[1]);
        d[n] = sgn(sn) as i8;
        let diagonal = event_xy(d[0], d[1]);
        for slot in out.iter_mut().take(count) {
            f += em;
            em += E_GROWTH;
            pm += sm;
            // 2 F at the midpoint between the minor and its next grid line.
            let g = 2 * f + en - 32_768;
            *slot = if (g > 0) == inward {
                f += en;
                en += E_GROWTH;
                pn += sn;
                diagonal
            } else {
                straight
            };
        }
        self.p[m] = pm;
        self.p[n] = pn;
        self.e[m] = em;
        self.e[n] = en;
        self.f = f;
        self.piece.left -= count as u32;
        self.moved |= count > 0;
        count
    }

    /// One classic step event, or `None` when the quadrant is left (a new piece begins).
    fn classic_tick(&mut self) -> Option<StepEvent> {
        let i = if self.f >= 0 {
            self.piece.major
        } else {
            1 - self.piece.major
        };
        // On an axis only the other axis makes progress.
        let i = if self.p[1 - i] == 0 && self.p[i] != 0 {
            1 - i
        } else {
            i
        };
        if self.piece.last {
            // Do not pass the target's coordinate on this axis: the tail finishes.
            let past = (i64::from(self.target[i]) - i64::from(self.p[i])) * i64::from(self.dir[i]);
            if past <= 0 {
                return None;
            }
        }
        let before = sgn(self.p[i]);
        self.prev = self.p;
        self.f += self.e[i];
        self.e[i] += E_GROWTH;
        self.p[i] += self.dir[i];
        self.moved = true;
        let mut d = [0i8; 2];
        d[i] = sgn(self.dir[i]) as i8;
        if self.p == self.target && self.piece.last {
            self.leg = Leg::Done;
        } else if sgn(self.p[i]) != before && i == self.piece.major {
            // The inward axis crossed (or reached) the centre's line: next quadrant.
            self.piece.left = 0;
        }
        Some(event_xy(d[0], d[1]))
    }

    /// Fills `out` with the next step events of the present piece; the count (0 when done). A
    /// DDA piece is filled in one tight loop; classic and tail step events come one by one.
    pub fn ticks(&mut self, out: &mut [StepEvent]) -> usize {
        loop {
            match &mut self.leg {
                Leg::Done => return 0,
                Leg::Settle(left) => {
                    let Some(slot) = out.first_mut() else {
                        return 0;
                    };
                    let sigma = sgn(*left);
                    *left -= sigma;
                    if *left == 0 {
                        self.leg = Leg::Trace;
                    }
                    *slot = self.settle_tick(sigma);
                    return 1;
                }
                Leg::Tail(line) => {
                    let Some(t) = line.next_event() else {
                        self.leg = Leg::Done;
                        return 0;
                    };
                    let Some(slot) = out.first_mut() else {
                        return 0;
                    };
                    let dl = t.deltas();
                    self.prev = self.p;
                    self.p[0] += i32::from(dl[0]) * ONE;
                    self.p[1] += i32::from(dl[1]) * ONE;
                    *slot = t;
                    return 1;
                }
                Leg::Trace => {}
            }
            if out.is_empty() {
                return 0;
            }
            match self.method {
                Method::Dda => {
                    if self.piece.left == 0 {
                        self.next_piece();
                        continue;
                    }
                    return self.dda_ticks(out);
                }
                Method::Classic => {
                    if self.piece.left == 0 {
                        self.next_piece();
                        continue;
                    }
                    match self.classic_tick() {
                        Some(t) => {
                            out[0] = t;
                            return 1;
                        }
                        None => self.start_tail(),
                    }
                }
            }
        }
    }

    /// Path length of the last step event, steps (classic and tail step events, timed one by one):
    /// along the circle, the radius times the angle between the points before and after
    /// (the angles add up to the arc's); along the tail, its straight length.
    pub fn last_tick_len(&self) -> f32 {
        let s = 1.0 / ONE as f32;
        let (a, b) = (self.prev, self.p);
        if !matches!(self.leg, Leg::Trace) || self.method == Method::Dda {
            let (dx, dy) = ((b[0] - a[0]) as f32 * s, (b[1] - a[1]) as f32 * s);
            return crate::fmath::sqrt(dx * dx + dy * dy);
        }
        let (ax, ay, bx, by) = (
            a[0] as f32 * s,
            a[1] as f32 * s,
            b[0] as f32 * s,
            b[1] as f32 * s,
        );
        let cross = ax * by - bx * ay;
        let dot = ax * bx + ay * by;
        self.radius * crate::fmath::abs(crate::fmath::atan2(cross, dot))
    }
}

impl Interpolate for Circle {
    fn next_event(&mut self) -> Option<StepEvent> {
        let mut one = [StepEvent(0)];
        (self.ticks(&mut one) == 1).then_some(one[0])
    }
}

#[cfg(test)]
mod tests;
