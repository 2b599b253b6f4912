//! Straight lines in up to three axes.
//!
//! [`DdaLine`] is Bresenham's algorithm generalised to three axes: the axis with the
//! longest travel steps on every step event, each other axis steps when its exact position
//! `k * d_i / D` rounds to the next integer, so every position is the nearest grid
//! point to the line at that major-axis coordinate (per-axis error <= 0.5).
//!
//! [`ClassicLine`] is the lab report's point-by-point comparison, F = y*xe - x*ye,
//! generalised: the axis whose progress `s_i / |d_i|` lags most steps next (ties go to
//! the lower axis, which is the report's "F >= 0: step X"). One axis per step event,
//! |dx| + |dy| + |dz| step events, within 1 step of the line (in 3D: less than one step on
//! every axis from some point of the line).
//!
//! Counters are u32: every travel of two i32 positions fits, and the DDA's doubled
//! remainders fit as long as the travel is below 2^31 steps, which the planner
//! guarantees ([`crate::motion::POS_LIMIT`]: every move starts and ends within
//! +-2^30). Outside that range nothing panics; the step events are then simply wrong.

use super::{Interpolate, StepEvent};
use crate::motion::{StepPos, AXES};

/// Per-axis absolute travel and direction of a line.
fn travel(start: StepPos, target: StepPos) -> ([u32; AXES], [i8; AXES]) {
    let mut len = [0u32; AXES];
    let mut dir = [0i8; AXES];
    for i in 0..AXES {
        let d = i64::from(target[i]) - i64::from(start[i]);
        len[i] = d.unsigned_abs() as u32;
        dir[i] = super::sgn(d);
    }
    (len, dir)
}

/// Bresenham / DDA line: axes may step together.
#[derive(Clone, Debug)]
pub struct DdaLine {
    /// Per axis: what a step event without a step adds to the remainder (2 |d_i|) and the
    /// remainder from which the axis steps (2 D - 2 |d_i|, D the major travel).
    inc: [u32; AXES],
    thr: [u32; AXES],
    dir: [i8; AXES],
    /// Major-axis travel (number of step events).
    major: u32,
    /// Per-axis remainder 2 k |d_i| - (2 m_i - 1) D, in [0, 2 D).
    rem: [u32; AXES],
    done: u32,
}

impl DdaLine {
    pub fn new(start: StepPos, target: StepPos) -> Self {
        let (len, dir) = travel(start, target);
        let major = len.iter().copied().max().unwrap_or(0);
        // Shifts, not multiplications: no overflow check (the planner keeps 2 D < 2^32).
        DdaLine {
            inc: len.map(|l| l << 1),
            thr: len.map(|l| (major << 1).wrapping_sub(l << 1)),
            dir,
            major,
            rem: [major; AXES],
            done: 0,
        }
    }
    /// Number of step events the line takes.
    pub fn ticks(&self) -> u32 {
        self.major
    }
}

impl Interpolate for DdaLine {
    fn next_event(&mut self) -> Option<StepEvent> {
        if self.done >= self.major {
            return None;
        }
        self.done += 1;
        let mut d = [0i8; AXES];
        let axes = self
            .rem
            .iter_mut()
            .zip(self.inc.iter().zip(&self.thr))
            .zip(self.dir.iter().zip(d.iter_mut()));
        for ((rem, (&inc, &thr)), (&dir, delta)) in axes {
            // rem + inc >= 2 D: the axis steps and the remainder wraps by 2 D.
            if *rem >= thr {
                *rem -= thr;
                *delta = dir;
            } else {
                // Wrapping: cannot wrap for travels below 2^31 (and must not panic
                // for the meaningless longer ones).
                *rem = rem.wrapping_add(inc);
            }
        }
        Some(StepEvent::from_deltas(d))
    }
}

/// Point-by-point comparison line: one axis per step event.
///
/// The axis whose progress `taken_i / len_i` is least steps next, the lowest such axis
/// on a tie. Kept incrementally, as the lab report keeps its F: for each pair of axes
/// (0,1), (0,2), (1,2) the cross difference `g = taken_i len_j - taken_j len_i`
/// (negative or zero: axis i has come no further than j), which a step of i raises by
/// `len_j` and a step of j lowers by `len_i`. Choosing the next axis is then two or
/// three sign tests, with no multiplication (it runs once per step event, up to 100,000
/// times a second). A pair with an axis that does not move is held at a constant
/// that decides it: the moving axis always wins.
#[derive(Clone, Debug)]
pub struct ClassicLine {
    /// The cross differences of the pairs (0,1), (0,2), (1,2).
    g: [i64; 3],
    len: [u32; AXES],
    /// The step event of each axis (its direction).
    events: [StepEvent; AXES],
    /// Step events left.
    left: u64,
}

/// The decided value of a pair whose first axis does not move (the second always
/// wins); the negated value when only the second does not move. Steps never change it
/// (a non-moving axis adds nothing), and live values stay within +-2^62.
const DECIDED: i64 = i64::MAX;

impl ClassicLine {
    pub fn new(start: StepPos, target: StepPos) -> Self {
        let (len, dir) = travel(start, target);
        let pair = |i: usize, j: usize| match (len[i] > 0, len[j] > 0) {
            (false, _) => DECIDED,
            (true, false) => -DECIDED,
            (true, true) => 0,
        };
        ClassicLine {
            g: [pair(0, 1), pair(0, 2), pair(1, 2)],
            len,
            events: core::array::from_fn(|a| {
                let mut d = [0i8; AXES];
                d[a] = dir[a];
                StepEvent::from_deltas(d)
            }),
            left: len.iter().map(|&l| u64::from(l)).sum(),
        }
    }
}

impl Interpolate for ClassicLine {
    fn next_event(&mut self) -> Option<StepEvent> {
        self.left = self.left.checked_sub(1)?;
        // An axis that has finished is at progress 1, ahead of every unfinished one, so
        // while events are left it is never chosen.
        let g = &mut self.g;
        let len = |a: usize| i64::from(self.len[a]);
        let axis = if g[0] <= 0 && g[1] <= 0 {
            g[0] += len(1);
            g[1] += len(2);
            0
        } else if g[0] > 0 && g[2] <= 0 {
            g[0] -= len(0);
            g[2] += len(2);
            1
        } else {
            g[1] -= len(0);
            g[2] -= len(1);
            2
        };
        self.events.get(axis).copied()
    }
}

/// Largest |coordinate| (steps) for [`FineLine`], so that Q8 products fit in i64.
const FINE_LIMIT: i64 = 1 << 21;

/// XY line between ideal (sub-step) end points, in 1/256 step: at every integer
/// major-axis coordinate the minor axis takes the integer nearest the ideal line
/// (per-axis error <= 0.5 against the unrounded path). Incremental: the rounding
/// remainder is kept as an exact integer, one add and compare per step event.
#[derive(Clone, Debug)]
pub struct FineLine {
    /// Major axis index (0 = X, 1 = Y) and directions.
    major: usize,
    dir_maj: i32,
    /// Present integer position (major, minor) and the integer target (i32: within
    /// FINE_LIMIT).
    pos: (i32, i32),
    end: (i32, i32),
    /// Rounding state: desired minor `n`, remainder r in [0, 256 D), increment per step.
    n: i32,
    r: i64,
    inc: i64,
    den: i64,
    /// Minor-only steps before the first column (signed): a start more than a step off
    /// the line's first column catches up first.
    catch_up: i32,
    /// The step events of a column whose minor moves by -1, 0 and +1.
    column: [StepEvent; 3],
}

impl FineLine {
    /// `None` when the points are too far out or the ideal line has no length; use
    /// [`DdaLine`] then.
    pub fn new(start: StepPos, target: StepPos, from: [i32; 2], to: [i32; 2]) -> Option<Self> {
        let f = [i64::from(from[0]), i64::from(from[1])];
        let t = [i64::from(to[0]), i64::from(to[1])];
        for v in [start[0], start[1], target[0], target[1]] {
            if i64::from(v).abs() > FINE_LIMIT {
                return None;
            }
        }
        for v in f.iter().chain(t.iter()) {
            if v.abs() > FINE_LIMIT * 256 {
                return None;
            }
        }
        let (dx, dy) = (t[0] - f[0], t[1] - f[1]);
        let major = if dx.abs() >= dy.abs() { 0 } else { 1 };
        let minor = 1 - major;
        let d_maj = t[major] - f[major];
        if d_maj == 0 {
            return None;
        }
        let s = d_maj.signum();
        let den = d_maj.abs();
        let d_min = t[minor] - f[minor];
        let p0 = (i64::from(start[major]), i64::from(start[minor]));
        // L(m) * den, in Q8, at the start's major coordinate.
        let ld = f[minor] * den + (p0.0 * 256 - f[major]) * d_min * s;
        // n = floor((L + 128) / 256) = floor((L*den + 128 den) / (256 den)).
        let q = 256 * den;
        let num = ld + 128 * den;
        // Floor division without a 64-bit divide (not in the chip's instruction set):
        // an f32 estimate (within a few units: |n| < 2^22), corrected exactly below.
        let mut n = (num as f32 / q as f32) as i64;
        let mut r = num - n * q;
        while r < 0 {
            r += q;
            n -= 1;
        }
        while r >= q {
            r -= q;
            n += 1;
        }
        // Going one step along the major direction: L*den changes by 256 * d_min * s * dir,
        // and dir = s along the major axis, so by 256 * d_min.
        let dir_maj = if i64::from(target[major]) >= p0.0 {
            1
        } else {
            -1
        };
        let inc = 256 * d_min * s * dir_maj;
        let mut line = FineLine {
            major,
            dir_maj: dir_maj as i32,
            pos: (start[major], start[minor]),
            end: (target[major], target[minor]),
            n: n as i32,
            r,
            inc,
            den: q,
            catch_up: 0,
            column: [StepEvent(0); 3],
        };
        line.column = [-1, 0, 1].map(|g| line.tick(line.dir_maj, g));
        if line.pos.0 != line.end.0 {
            let gap = line.next_minor().0 - line.pos.1;
            line.catch_up = gap - gap.signum();
        }
        Some(line)
    }

    /// Desired minor at the next major coordinate, and the remainder there (|inc| <=
    /// den: the minor moves at most one step per column).
    #[inline(always)]
    fn next_minor(&self) -> (i32, i64) {
        let r = self.r + self.inc;
        if r >= self.den {
            (self.n + 1, r - self.den)
        } else if r < 0 {
            (self.n - 1, r + self.den)
        } else {
            (self.n, r)
        }
    }

    /// Up to `out.len()` step events of the main run (no catch-up step pending, and at most
    /// the columns left): one remainder update per step event, in locals (the fields are
    /// written back once).
    fn run_into(&mut self, out: &mut [StepEvent]) -> usize {
        let (mut n, mut r, mut minor) = (self.n, self.r, self.pos.1);
        let (inc, den, column) = (self.inc, self.den, self.column);
        for slot in out.iter_mut() {
            r += inc;
            if r >= den {
                r -= den;
                n += 1;
            } else if r < 0 {
                r += den;
                n -= 1;
            }
            // After the catch-up the minor moves by at most one: the index is 0..=2.
            *slot = column[((n - minor + 1) as usize).min(2)];
            minor = n;
        }
        (self.n, self.r, self.pos.1) = (n, r, minor);
        self.pos.0 += self.dir_maj * out.len() as i32;
        out.len()
    }

    /// Minor-only steps still to come before the first column or after the last.
    fn extra_ticks(&self) -> bool {
        self.catch_up != 0 || (self.pos.0 == self.end.0 && self.pos.1 != self.end.1)
    }

    fn tick(&self, d_maj: i32, d_min: i32) -> StepEvent {
        let (d_maj, d_min) = (d_maj as i8, d_min as i8);
        if self.major == 0 {
            super::event_xy(d_maj, d_min)
        } else {
            super::event_xy(d_min, d_maj)
        }
    }
}

impl Interpolate for FineLine {
    fn next_event(&mut self) -> Option<StepEvent> {
        if self.catch_up != 0 {
            // Steeper than one step per column right at the start: catch up first.
            let s = self.catch_up.signum();
            self.catch_up -= s;
            self.pos.1 += s;
            return Some(self.tick(0, s));
        }
        if self.pos.0 != self.end.0 {
            let (n, r) = self.next_minor();
            let gap = n - self.pos.1;
            self.n = n;
            self.r = r;
            self.pos.0 += self.dir_maj;
            self.pos.1 += gap;
            return Some(self.tick(self.dir_maj, gap));
        }
        if self.pos.1 != self.end.1 {
            // The target (the ideal end rounded) is a step off the line's last column.
            let s = (self.end.1 - self.pos.1).signum();
            self.pos.1 += s;
            return Some(self.tick(0, s));
        }
        None
    }
}

/// A line in either method.
#[derive(Clone, Debug)]
pub enum Line {
    Dda(DdaLine),
    Classic(ClassicLine),
    Fine(FineLine),
}

impl Line {
    pub fn new(start: StepPos, target: StepPos, method: super::Method) -> Self {
        match method {
            super::Method::Dda => Line::Dda(DdaLine::new(start, target)),
            super::Method::Classic => Line::Classic(ClassicLine::new(start, target)),
        }
    }
}

impl Line {
    /// Step events that advance along the line (the major-axis count for DDA, every step for
    /// classic), each by the same length. A fine line may add a catch-up step at either
    /// end.
    pub fn ticks(&self) -> u64 {
        match self {
            Line::Dda(l) => u64::from(l.major),
            Line::Classic(l) => l.len.iter().map(|&v| u64::from(v)).sum(),
            Line::Fine(l) => u64::from((l.end.0 - l.pos.0).unsigned_abs()),
        }
    }

    /// What comes next: a run of equal step events, a catch-up step, or nothing.
    pub fn next(&self) -> super::Next {
        let left = match self {
            Line::Dda(l) => l.major - l.done,
            Line::Classic(l) => u32::try_from(l.left).unwrap_or(u32::MAX),
            Line::Fine(l) if l.extra_ticks() => return super::Next::Extra,
            Line::Fine(l) => (l.end.0 - l.pos.0).unsigned_abs(),
        };
        if left == 0 {
            super::Next::Done
        } else {
            super::Next::Run(left)
        }
    }

    /// Up to `out.len()` step events of the present run (or the one catch-up step).
    pub fn events_into(&mut self, out: &mut [StepEvent]) -> usize {
        match self {
            Line::Dda(l) => fill(l, out),
            Line::Classic(l) => fill(l, out),
            Line::Fine(l) if l.extra_ticks() => fill(l, out.get_mut(..1).unwrap_or(&mut [])),
            Line::Fine(l) => {
                let left = (l.end.0 - l.pos.0).unsigned_abs() as usize;
                l.run_into(out.get_mut(..left.min(out.len())).unwrap_or(&mut []))
            }
        }
    }
}

/// Fills `out` from `it` (one monomorphic loop per interpolator): the count written.
#[inline(always)]
pub(crate) fn fill(it: &mut impl Interpolate, out: &mut [StepEvent]) -> usize {
    let mut n = 0;
    for slot in out.iter_mut() {
        match it.next_event() {
            Some(t) => *slot = t,
            None => break,
        }
        n += 1;
    }
    n
}

impl Interpolate for Line {
    fn next_event(&mut self) -> Option<StepEvent> {
        match self {
            Line::Dda(l) => l.next_event(),
            Line::Classic(l) => l.next_event(),
            Line::Fine(l) => l.next_event(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interpolation::Interpolate;
    use proptest::prelude::*;

    fn run(mut it: impl Interpolate, start: StepPos) -> std::vec::Vec<StepPos> {
        let mut p = start;
        let mut out = std::vec![p];
        while let Some(t) = it.next_event() {
            t.apply(&mut p);
            out.push(p);
        }
        out
    }

    /// Largest per-axis distance from `p` to the point of the ideal segment with the
    /// same major-axis coordinate (DDA criterion).
    fn dda_error(start: StepPos, target: StepPos, p: StepPos) -> f64 {
        let d: std::vec::Vec<f64> = (0..AXES)
            .map(|i| f64::from(target[i]) - f64::from(start[i]))
            .collect();
        let m = (0..AXES)
            .max_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs()))
            .unwrap();
        if d[m] == 0.0 {
            return 0.0;
        }
        let t = (f64::from(p[m]) - f64::from(start[m])) / d[m];
        (0..AXES)
            .map(|i| (f64::from(start[i]) + t * d[i] - f64::from(p[i])).abs())
            .fold(0.0, f64::max)
    }

    /// Euclidean distance from `p` to the segment.
    fn seg_dist(start: StepPos, target: StepPos, p: StepPos) -> f64 {
        let d: std::vec::Vec<f64> = (0..AXES)
            .map(|i| f64::from(target[i]) - f64::from(start[i]))
            .collect();
        let w: std::vec::Vec<f64> = (0..AXES)
            .map(|i| f64::from(p[i]) - f64::from(start[i]))
            .collect();
        let dd: f64 = d.iter().map(|v| v * v).sum();
        let t = if dd == 0.0 {
            0.0
        } else {
            (d.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>() / dd).clamp(0.0, 1.0)
        };
        (0..AXES)
            .map(|i| (w[i] - t * d[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// Is there a point of the segment within less than one step of `p` on every axis?
    fn per_axis_within_one(start: StepPos, target: StepPos, p: StepPos) -> bool {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for i in 0..AXES {
            let d = f64::from(target[i]) - f64::from(start[i]);
            let w = f64::from(p[i]) - f64::from(start[i]);
            if d == 0.0 {
                if w.abs() >= 1.0 {
                    return false;
                }
                continue;
            }
            let (a, b) = ((w - 1.0) / d, (w + 1.0) / d);
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
        }
        lo < hi
    }

    fn pos() -> impl Strategy<Value = StepPos> {
        [-5000i32..5000, -5000i32..5000, -200i32..200]
    }

    #[test]
    fn octant_lines_end_exactly_with_expected_tick_counts() {
        for &(tx, ty) in &[
            (7, 3),
            (3, 7),
            (-7, 3),
            (-3, -7),
            (7, -3),
            (0, 5),
            (-5, 0),
            (4, 4),
        ] {
            let t = [tx, ty, 0];
            let dda = run(DdaLine::new([0; 3], t), [0; 3]);
            assert_eq!(*dda.last().unwrap(), t);
            assert_eq!(dda.len() - 1, tx.abs().max(ty.abs()) as usize);
            let cl = run(ClassicLine::new([0; 3], t), [0; 3]);
            assert_eq!(*cl.last().unwrap(), t);
            assert_eq!(cl.len() - 1, (tx.abs() + ty.abs()) as usize);
        }
    }

    #[test]
    fn classic_first_quadrant_matches_the_lab_report_f_rule() {
        // F = y*xe - x*ye; F >= 0 -> +X (F -= ye), else +Y (F += xe).
        let (xe, ye) = (5i64, 3i64);
        let (mut x, mut y, mut f) = (0i64, 0i64, 0i64);
        let mut expect = std::vec::Vec::new();
        while x < xe || y < ye {
            if f >= 0 && x < xe || y >= ye {
                x += 1;
                f -= ye;
            } else {
                y += 1;
                f += xe;
            }
            expect.push([x as i32, y as i32, 0]);
        }
        let got = run(ClassicLine::new([0; 3], [5, 3, 0]), [0; 3]);
        assert_eq!(&got[1..], &expect[..]);
    }

    /// The DDA line as it was with i64 error terms (2 k |d_i| - (2 m_i + 1) D in
    /// [-2 D, 0)): the u32 remainders must give the same step events.
    fn i64_dda(start: StepPos, target: StepPos) -> impl Iterator<Item = StepEvent> {
        let len: std::vec::Vec<i64> = (0..AXES)
            .map(|i| (i64::from(target[i]) - i64::from(start[i])).abs())
            .collect();
        let dir: std::vec::Vec<i8> = (0..AXES)
            .map(|i| crate::interpolation::sgn(i64::from(target[i]) - i64::from(start[i])))
            .collect();
        let major = len.iter().copied().max().unwrap_or(0);
        let mut err = [-major; AXES];
        (0..major).map(move |_| {
            let mut d = [0i8; AXES];
            for i in 0..AXES {
                err[i] += 2 * len[i];
                if err[i] >= 0 {
                    err[i] -= 2 * major;
                    d[i] = dir[i];
                }
            }
            StepEvent::from_deltas(d)
        })
    }

    #[test]
    fn u32_dda_matches_the_i64_error_terms_at_the_range_limit() {
        // Travels up to 2^31 - 2 (ends at +-(2^30 - 1)): the first step events and a
        // window after a long run agree.
        let e = (1 << 30) - 1;
        let cases = [
            ([e, -e, 0], [-e, e, 17]),
            ([-e, 0, 5], [e, 12345, -e]),
            ([0, 0, 0], [e, e - 1, 1]),
            ([-e, -e, -e], [e, 3, e - 7]),
        ];
        for (s, t) in cases {
            let mut l = DdaLine::new(s, t);
            assert_eq!(u64::from(l.ticks()), i64_dda(s, t).size_hint().0 as u64);
            for (k, want) in i64_dda(s, t).take(200_000).enumerate() {
                assert_eq!(l.next_event(), Some(want), "{s:?} -> {t:?} tick {k}");
            }
        }
    }

    /// The point-by-point rule stated directly (the implementation before the
    /// incremental one): the unfinished axis of least progress `taken / len`, compared
    /// by cross-multiplication, the lowest on a tie.
    fn reference_classic_axis(len: &[u32; AXES], taken: &[u32; AXES]) -> Option<usize> {
        let mut best: Option<usize> = None;
        for i in 0..AXES {
            if taken[i] >= len[i] {
                continue;
            }
            best = match best {
                Some(b)
                    if u64::from(taken[i]) * u64::from(len[b])
                        >= u64::from(taken[b]) * u64::from(len[i]) =>
                {
                    Some(b)
                }
                _ => Some(i),
            };
        }
        best
    }

    proptest! {
        #[test]
        fn u32_dda_matches_the_i64_error_terms(s in prop::array::uniform3(-3000i32..3000), t in prop::array::uniform3(-3000i32..3000)) {
            let got: std::vec::Vec<StepEvent> = {
                let mut l = DdaLine::new(s, t);
                std::iter::from_fn(|| l.next_event()).collect()
            };
            let want: std::vec::Vec<StepEvent> = i64_dda(s, t).collect();
            prop_assert_eq!(got, want);
        }

        #[test]
        fn fine_lines_follow_the_unrounded_line(fx in -400_000i32..400_000, fy in -400_000i32..400_000,
                                                 tx in -400_000i32..400_000, ty in -400_000i32..400_000) {
            let round = |q: i32| (f64::from(q) / 256.0).round() as i32;
            let start = [round(fx), round(fy), 0];
            let target = [round(tx), round(ty), 0];
            prop_assume!((fx, fy) != (tx, ty));
            let it = FineLine::new(start, target, [fx, fy], [tx, ty]).unwrap();
            let pts = run(it, start);
            prop_assert_eq!(*pts.last().unwrap(), target);
            let (sx, sy) = (f64::from(fx) / 256.0, f64::from(fy) / 256.0);
            let (ex, ey) = (f64::from(tx) / 256.0, f64::from(ty) / 256.0);
            // Every position within half a step on both axes of some point of the ideal
            // segment, except possibly one catch-up step at each end.
            let mut off = 0;
            for p in &pts {
                let (px, py) = (f64::from(p[0]), f64::from(p[1]));
                let (dx, dy) = (ex - sx, ey - sy);
                let mut lo = 0.0f64;
                let mut hi = 1.0f64;
                for (d, w) in [(dx, px - sx), (dy, py - sy)] {
                    if d.abs() < 1e-12 {
                        if w.abs() > 0.5 + 1e-9 { lo = 2.0; }
                        continue;
                    }
                    let (a, b) = ((w - 0.5 - 1e-9) / d, (w + 0.5 + 1e-9) / d);
                    lo = lo.max(a.min(b));
                    hi = hi.min(a.max(b));
                }
                if lo > hi { off += 1; }
            }
            prop_assert!(off <= 2, "{} positions off", off);
            for w in pts.windows(2) {
                prop_assert!((w[0][0] - w[1][0]).abs() <= 1 && (w[0][1] - w[1][1]).abs() <= 1);
            }
        }

        #[test]
        fn dda_lines_are_exact(start in pos(), target in pos()) {
            let pts = run(DdaLine::new(start, target), start);
            prop_assert_eq!(*pts.last().unwrap(), target);
            for p in &pts {
                prop_assert!(dda_error(start, target, *p) <= 0.5 + 1e-9, "{:?}", p);
            }
        }

        #[test]
        fn classic_lines_choose_as_the_cross_multiplied_rule(
            start in pos(),
            target in pos(),
            still in 0u8..8,
        ) {
            // Some axes not moving at all (bit i: axis i stays), as planar moves do.
            let target: StepPos = core::array::from_fn(|i| if still >> i & 1 != 0 { start[i] } else { target[i] });
            let (len, dir) = travel(start, target);
            let mut it = ClassicLine::new(start, target);
            let mut taken = [0u32; AXES];
            loop {
                let want = reference_classic_axis(&len, &taken);
                let got = it.next_event();
                match want {
                    None => {
                        prop_assert_eq!(got, None);
                        break;
                    }
                    Some(a) => {
                        let mut d = [0i8; AXES];
                        d[a] = dir[a];
                        prop_assert_eq!(got, Some(StepEvent::from_deltas(d)), "after {:?}", taken);
                        taken[a] += 1;
                    }
                }
            }
        }

        #[test]
        fn classic_lines_step_one_axis_within_one_step(start in pos(), target in pos()) {
            let mut it = ClassicLine::new(start, target);
            let mut p = start;
            let mut n = 0i64;
            while let Some(t) = it.next_event() {
                prop_assert_eq!(t.steps().count_ones(), 1);
                t.apply(&mut p);
                n += 1;
                if start[2] == target[2] {
                    prop_assert!(seg_dist(start, target, p) < 1.0, "{:?}", p);
                } else {
                    prop_assert!(per_axis_within_one(start, target, p), "{:?}", p);
                }
            }
            prop_assert_eq!(p, target);
            let manhattan: i64 = (0..AXES).map(|i| (i64::from(target[i]) - i64::from(start[i])).abs()).sum();
            prop_assert_eq!(n, manhattan);
        }
    }
}
