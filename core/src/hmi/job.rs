//! The keypad drawing jobs (the lab report's modes) and how each becomes planner moves.
//!
//! A [`Job`] holds the user's parameters in mm and degrees, relative to the pen position
//! when it starts (as in the report, whose shapes all start where the pen is). It owns
//! two things: [`Job::plan`] turns it into [`Move`]s in integer steps (pen down, the
//! path, pen up) for the planner, and [`Job::point_at`] gives the ideal curve for the
//! LCD preview and the progress estimate. Both come from the same parameters so the
//! preview shows exactly what will be drawn.
//!
//! Pen up/down are Z moves ([`Config::pen_up_mm`], [`Config::pen_down_mm`]), so the
//! whole job is one ordered move stream and every XY move carries the pen-down Z.

use crate::fmath;
use core::f32::consts::PI;

use super::{Action, Actions, Config};
use crate::motion::{Feed, Move, Path, StepPos, X, Y, Z};

/// One drawing job, parameters in mm / degrees, relative to the start position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Job {
    /// Straight line by (dx, dy): the sign picks the quadrant.
    Line { dx: f32, dy: f32 },
    /// Circular arc of radius `r` starting at its 0° point (centre at -r on X), through
    /// `theta` degrees: positive counter-clockwise, negative clockwise, ±360 a circle.
    Arc { r: f32, theta: f32 },
    /// Full ellipse with semi-axes `a` (X) and `b` (Y), counter-clockwise, starting at
    /// its rightmost point.
    Ellipse { a: f32, b: f32 },
    /// y = amp sin(omega x + phase) - amp sin(phase) for x in [0, len] mm; `omega` in
    /// rad/mm, `phase` in degrees.
    Sine {
        amp: f32,
        omega: f32,
        phase: f32,
        len: f32,
    },
    /// Five-pointed star {5/2} drawn continuously from its top point; `size` is the
    /// diameter of the circle through the five points.
    Star { size: f32 },
    /// Pen-up rapid travel by (dx, dy) (go to origin).
    Travel { dx: f32, dy: f32 },
}

/// Why a job cannot be planned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobError {
    /// Nothing would move (zero length or zero angle).
    Empty,
    /// A coordinate does not fit the step counter.
    TooLarge,
}

impl JobError {
    pub fn message(self) -> &'static str {
        match self {
            JobError::Empty => "Nothing to draw",
            JobError::TooLarge => "Out of range",
        }
    }
}

/// `v` steps rounded to whole steps; None if not finite or 10^9 or more (which keeps
/// sums far from i32 overflow).
fn steps(v: f32) -> Option<i32> {
    super::fixed::round_checked(v)
}

/// [`steps`], out of range as the job error.
fn steps_or_err(v: f32) -> Result<i32, JobError> {
    steps(v).ok_or(JobError::TooLarge)
}

/// (cos, sin) of star point k's angle, pi/2 - k 4pi/5 (top point first, every second
/// vertex), k = 0..=5: the exact f32 values of libm's cosf/sinf (checked in the tests),
/// so the star needs no trigonometry at run time.
const STAR: [[f32; 2]; 6] = [
    [f32::from_bits(0xb33b_bd2e), f32::from_bits(0x3f80_0000)],
    [f32::from_bits(0x3f16_7918), f32::from_bits(0xbf4f_1bbd)],
    [f32::from_bits(0xbf73_7871), f32::from_bits(0x3e9e_3779)],
    [f32::from_bits(0x3f73_7871), f32::from_bits(0x3e9e_3778)],
    [f32::from_bits(0xbf16_7920), f32::from_bits(0xbf4f_1bb7)],
    [f32::from_bits(0x3532_22c4), f32::from_bits(0x3f80_0000)],
];

/// Star point k of a star of circumradius `r`, relative to its top point.
fn star_point(r: f32, k: usize) -> [f32; 2] {
    let [c, s] = STAR.get(k).copied().unwrap_or([0.0, 1.0]);
    [r * c, r * s - r]
}

/// A point of the ellipse with semi-axes (a, b) at `angle` (radians) from its 0° point,
/// relative to that point.
fn conic_point(a: f32, b: f32, angle: f32) -> [f32; 2] {
    [a * fmath::cos(angle) - a, b * fmath::sin(angle)]
}

impl Job {
    /// Short name for titles.
    pub fn name(&self) -> &'static str {
        match self {
            Job::Line { .. } => "Line",
            Job::Arc { .. } => "Arc",
            Job::Ellipse { .. } => "Ellipse",
            Job::Sine { .. } => "Sine",
            Job::Star { .. } => "Star",
            Job::Travel { .. } => "Go to origin",
        }
    }

    /// The variant (0..=5) and the parameters' bit patterns (unused ones 0): an exact
    /// identity for the job without float comparisons.
    pub fn words(&self) -> (u32, [u32; 4]) {
        let (kind, v) = match *self {
            Job::Line { dx, dy } => (0, [dx, dy, 0.0, 0.0]),
            Job::Arc { r, theta } => (1, [r, theta, 0.0, 0.0]),
            Job::Ellipse { a, b } => (2, [a, b, 0.0, 0.0]),
            Job::Sine {
                amp,
                omega,
                phase,
                len,
            } => (3, [amp, omega, phase, len]),
            Job::Star { size } => (4, [size, 0.0, 0.0, 0.0]),
            Job::Travel { dx, dy } => (5, [dx, dy, 0.0, 0.0]),
        };
        (kind, v.map(f32::to_bits))
    }

    /// Whether the pen is down while this job moves.
    pub fn draws(&self) -> bool {
        !matches!(self, Job::Travel { .. })
    }

    /// The ideal path point at parameter `t` in [0, 1], in mm relative to the start.
    pub fn point_at(&self, t: f32) -> [f32; 2] {
        let t = t.clamp(0.0, 1.0);
        // The arc and the ellipse share one conic evaluation: (a, b, angle).
        let (a, b, angle) = match *self {
            Job::Line { dx, dy } | Job::Travel { dx, dy } => return [dx * t, dy * t],
            Job::Arc { r, theta } => (r, r, theta.to_radians() * t),
            Job::Ellipse { a, b } => (a, b, 2.0 * PI * t),
            Job::Sine {
                amp,
                omega,
                phase,
                len,
            } => {
                let x = len * t;
                let ph = phase.to_radians();
                return [x, amp * fmath::sin(omega * x + ph) - amp * fmath::sin(ph)];
            }
            Job::Star { size } => {
                let r = size / 2.0;
                let s = t * 5.0;
                // s >= 0: the cast is the floor.
                let k = (s as usize).min(4);
                let f = s - k as f32;
                let (p0, p1) = (star_point(r, k), star_point(r, k + 1));
                return [p0[0] + (p1[0] - p0[0]) * f, p0[1] + (p1[1] - p0[1]) * f];
            }
        };
        conic_point(a, b, angle)
    }

    /// Path length in mm (chords of 160 samples, a multiple of the star's 5 sides, so
    /// exact for lines and the star).
    pub fn length_mm(&self) -> f32 {
        self.sweep().2
    }

    /// Bounding box (min, max) of the path in mm relative to the start.
    pub fn bounds(&self) -> ([f32; 2], [f32; 2]) {
        let (lo, hi, _) = self.sweep();
        (lo, hi)
    }

    /// Bounds (min, max) and length from one pass over 160 samples of the path.
    pub fn sweep(&self) -> ([f32; 2], [f32; 2], f32) {
        const N: usize = 160;
        let mut lo = [0.0f32; 2];
        let mut hi = [0.0f32; 2];
        let mut len = 0.0;
        let mut prev = self.point_at(0.0);
        for i in 0..N + 1 {
            let p = self.point_at(i as f32 / N as f32);
            if i > 0 {
                len += fmath::hypot(p[0] - prev[0], p[1] - prev[1]);
            }
            prev = p;
            for ax in 0..2 {
                lo[ax] = lo[ax].min(p[ax]);
                hi[ax] = hi[ax].max(p[ax]);
            }
        }
        (lo, hi, len)
    }

    /// Queue this job's planner moves from `start` (pen down, path, pen up) in `out`
    /// as [`Action::Queue`]s (at most 7: pen down, five star lines, pen up) and return
    /// where it ends. On an error `out` is left as it was.
    pub fn plan(
        &self,
        start: StepPos,
        cfg: &Config,
        out: &mut Actions,
    ) -> Result<StepPos, JobError> {
        let n = out.len();
        let r = self.plan_moves(start, cfg, out);
        if r.is_err() {
            out.truncate(n);
        }
        r
    }

    fn plan_moves(
        &self,
        start: StepPos,
        cfg: &Config,
        out: &mut Actions,
    ) -> Result<StepPos, JobError> {
        use JobError::Empty;
        let spmm = cfg.steps_per_mm;
        let z_down = steps_or_err(cfg.pen_down_mm * spmm[Z])?;
        let z_up = steps_or_err(cfg.pen_up_mm * spmm[Z])?;
        let draws = self.draws();
        let (z, feed) = if draws {
            (z_down, Feed::MmPerMin(cfg.draw_feed_mm_min))
        } else {
            (z_up, Feed::Rapid)
        };
        // Pen to its working height at the start point first.
        let here = [start[X], start[Y], z];
        add(out, here, Path::Line, Feed::Rapid)?;
        // A straight line to `d` mm from the start; if `must_move`, refused if it
        // would not move (a drawn line; going to the origin from there is fine).
        let line_to = |out: &mut Actions, d: [f32; 2], must_move: bool| {
            let rel = [steps_or_err(d[0] * spmm[X])?, steps_or_err(d[1] * spmm[Y])?];
            if must_move && rel == [0, 0] {
                return Err(Empty);
            }
            add_rel(out, here, rel, Path::Line, feed)
        };
        // The arc and the ellipse share one conic: (semi-axes in mm, angle).
        let mut conic_mm = None;
        match *self {
            Job::Line { dx, dy } | Job::Travel { dx, dy } => line_to(out, [dx, dy], draws)?,
            Job::Arc { r, theta } => {
                if theta == 0.0 {
                    return Err(Empty);
                }
                conic_mm = Some((r, r, theta));
            }
            Job::Ellipse { a, b } => conic_mm = Some((a, b, 360.0)),
            Job::Sine {
                amp,
                omega,
                phase,
                len,
            } => {
                let amp_steps = amp * spmm[Y];
                let omega_steps = omega / spmm[X];
                let ph = phase.to_radians();
                let len_steps = steps_or_err(len * spmm[X])?;
                if len_steps == 0 {
                    return Err(Empty);
                }
                let rise = amp_steps * fmath::sin(omega_steps * len_steps as f32 + ph)
                    - amp_steps * fmath::sin(ph);
                let path = Path::Sine {
                    amp: amp_steps,
                    omega: omega_steps,
                    phase: ph,
                };
                add_rel(out, here, [len_steps, steps_or_err(rise)?], path, feed)?;
            }
            Job::Star { size } => {
                let r = size / 2.0;
                if steps_or_err(r * spmm[X])? == 0 {
                    return Err(Empty);
                }
                for k in 1..5 {
                    line_to(out, star_point(r, k), false)?;
                }
                // The fifth line closes exactly on the start.
                add(out, here, Path::Line, feed)?;
            }
        }
        if let Some((a, b, theta)) = conic_mm {
            conic(out, here, [a * spmm[X], b * spmm[Y]], theta, feed)?;
        }
        // Where the path ended (its last move), with the pen lifted.
        let last = match out.last() {
            Some(Action::Queue(m)) => m.target,
            _ => here,
        };
        let end = [last[X], last[Y], z_up];
        if draws {
            add(out, end, Path::Line, Feed::Rapid)?;
        }
        Ok(end)
    }
}

/// Append a move (no room: the job is too complex, which the fixed jobs never are).
fn add(out: &mut Actions, target: StepPos, path: Path, feed: Feed) -> Result<(), JobError> {
    let m = Move {
        target,
        path,
        feed,
        line: 0,
    };
    out.push(Action::Queue(m)).map_err(|_| JobError::TooLarge)
}

/// Append a move to `from` + `rel` (X, Y in steps) at `from`'s pen height.
fn add_rel(
    out: &mut Actions,
    from: StepPos,
    rel: [i32; 2],
    path: Path,
    feed: Feed,
) -> Result<(), JobError> {
    let to = |a: usize| from[a].checked_add(rel[a]).ok_or(JobError::TooLarge);
    add(out, [to(X)?, to(Y)?, from[Z]], path, feed)
}

/// Arc or ellipse from `from` (its 0° point) through `theta` degrees, semi-axes `semi`
/// in steps (rounded here). A circle in mm is a circle in steps only when X and Y have
/// the same steps/mm; otherwise it is sent as an ellipse. Full turns go as two half
/// turns so that no move has target == start.
fn conic(
    out: &mut Actions,
    from: StepPos,
    semi: [f32; 2],
    theta: f32,
    feed: Feed,
) -> Result<(), JobError> {
    use JobError::{Empty, TooLarge};
    let a = steps_or_err(semi[0])?;
    let b = steps_or_err(semi[1])?;
    if a <= 0 || b <= 0 {
        return Err(Empty);
    }
    // The centre (a to the left of the start) must be a position too.
    from[X].checked_sub(a).ok_or(TooLarge)?;
    let ccw = theta > 0.0;
    // The centre relative to a point `rel` from the start.
    let path = |rel: [i32; 2]| {
        let center = [-a - rel[0], -rel[1]];
        if a == b {
            Path::Arc {
                center,
                ccw,
                turns: 0,
            }
        } else {
            Path::Ellipse { center, a, b, ccw }
        }
    };
    if theta.abs() >= 360.0 {
        // Exactly opposite the start, then back.
        add_rel(out, from, [-2 * a, 0], path([0, 0]), feed)?;
        return add(out, from, path([-2 * a, 0]), feed);
    }
    let t = theta.to_radians();
    let rel = [
        steps_or_err(a as f32 * fmath::cos(t))? - a,
        steps_or_err(b as f32 * fmath::sin(t))?,
    ];
    add_rel(out, from, rel, path([0, 0]), feed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The moves of a plan and where it ends.
    #[derive(Debug, PartialEq)]
    struct Plan {
        moves: std::vec::Vec<Move>,
        end: StepPos,
    }

    impl Job {
        /// [`Job::plan`] into a fresh list, as moves.
        fn planned(&self, start: StepPos, cfg: &Config) -> Result<Plan, JobError> {
            let mut out = Actions::new();
            let end = self.plan(start, cfg, &mut out)?;
            let moves = out
                .iter()
                .map(|a| match a {
                    Action::Queue(m) => *m,
                    other => panic!("not a move: {other:?}"),
                })
                .collect();
            Ok(Plan { moves, end })
        }
    }

    fn cfg() -> Config {
        Config {
            steps_per_mm: [80.0, 80.0, 100.0],
            pen_up_mm: 5.0,
            pen_down_mm: 0.0,
            draw_feed_mm_min: 600.0,
        }
    }

    #[test]
    fn line_in_each_quadrant_lands_on_the_rounded_target() {
        for (dx, dy) in [(10.0, 5.0), (-10.0, 5.0), (-10.0, -5.0), (10.0, -5.0)] {
            let plan = Job::Line { dx, dy }
                .planned([100, 200, 500], &cfg())
                .unwrap();
            let m = plan.moves.as_slice();
            assert_eq!(m.len(), 3);
            assert_eq!(m[0].target, [100, 200, 0], "pen down at the start");
            assert_eq!(
                m[1].target,
                [100 + (dx * 80.0) as i32, 200 + (dy * 80.0) as i32, 0]
            );
            assert_eq!(m[1].feed, Feed::MmPerMin(600.0));
            assert_eq!(m[2].target, [m[1].target[0], m[1].target[1], 500], "pen up");
            assert_eq!(plan.end, m[2].target);
        }
    }

    #[test]
    fn full_circle_is_two_half_arcs_with_centres_relative_to_each_start() {
        let plan = Job::Arc {
            r: 10.0,
            theta: 360.0,
        }
        .planned([0, 0, 0], &cfg())
        .unwrap();
        let m = plan.moves.as_slice();
        assert_eq!(m[1].target, [-1600, 0, 0]);
        assert_eq!(
            m[1].path,
            Path::Arc {
                center: [-800, 0],
                ccw: true,
                turns: 0
            }
        );
        assert_eq!(m[2].target, [0, 0, 0]);
        assert_eq!(
            m[2].path,
            Path::Arc {
                center: [800, 0],
                ccw: true,
                turns: 0
            }
        );
    }

    #[test]
    fn clockwise_quarter_arc_ends_below_the_centre() {
        let plan = Job::Arc {
            r: 10.0,
            theta: -90.0,
        }
        .planned([0, 0, 0], &cfg())
        .unwrap();
        let m = plan.moves.as_slice();
        assert_eq!(m[1].target, [-800, -800, 0]);
        assert_eq!(
            m[1].path,
            Path::Arc {
                center: [-800, 0],
                ccw: false,
                turns: 0
            }
        );
    }

    #[test]
    fn arc_with_unequal_steps_per_mm_becomes_an_ellipse_in_steps() {
        let mut c = cfg();
        c.steps_per_mm[Y] = 40.0;
        let plan = Job::Arc {
            r: 10.0,
            theta: 90.0,
        }
        .planned([0, 0, 0], &c)
        .unwrap();
        assert_eq!(
            plan.moves[1].path,
            Path::Ellipse {
                center: [-800, 0],
                a: 800,
                b: 400,
                ccw: true
            }
        );
        assert_eq!(plan.moves[1].target, [-800, 400, 0]);
    }

    #[test]
    fn sine_parameters_are_converted_to_steps_and_radians() {
        let job = Job::Sine {
            amp: 10.0,
            omega: 0.5,
            phase: 90.0,
            len: 20.0,
        };
        let plan = job.planned([0, 0, 0], &cfg()).unwrap();
        let m = plan.moves[1];
        let Path::Sine { amp, omega, phase } = m.path else {
            panic!("not a sine: {m:?}")
        };
        assert_eq!(amp, 800.0);
        assert!((omega - 0.5 / 80.0).abs() < 1e-9);
        assert!((phase - PI / 2.0).abs() < 1e-6);
        // y(20 mm) = 10 sin(10 + pi/2) - 10 = 10 cos(10) - 10 mm.
        let want_y = libm::roundf((10.0 * libm::cosf(10.0) - 10.0) * 80.0) as i32;
        assert_eq!(m.target, [1600, want_y, 0]);
    }

    #[test]
    fn star_closes_on_its_start_and_has_five_equal_sides() {
        let plan = Job::Star { size: 40.0 }
            .planned([1000, 1000, 0], &cfg())
            .unwrap();
        let m = plan.moves.as_slice();
        assert_eq!(m.len(), 7);
        assert_eq!(m[5].target, [1000, 1000, 0]);
        let side = 2.0 * 20.0 * libm::sinf(2.0 * PI / 5.0) * 80.0;
        let mut prev = [1000, 1000];
        for mv in &m[1..6] {
            let d = libm::hypotf(
                (mv.target[0] - prev[0]) as f32,
                (mv.target[1] - prev[1]) as f32,
            );
            assert!((d - side).abs() < 1.5, "side {d} vs {side}");
            prev = [mv.target[0], mv.target[1]];
        }
        assert!((Job::Star { size: 40.0 }.length_mm() - 5.0 * side / 80.0).abs() < 0.01);
    }

    #[test]
    fn degenerate_and_huge_jobs_are_refused() {
        assert_eq!(
            Job::Line { dx: 0.0, dy: 0.001 }.planned([0; 3], &cfg()),
            Err(JobError::Empty)
        );
        assert_eq!(
            Job::Arc { r: 5.0, theta: 0.0 }.planned([0; 3], &cfg()),
            Err(JobError::Empty)
        );
        assert_eq!(
            Job::Line { dx: 1.0e9, dy: 0.0 }.planned([0; 3], &cfg()),
            Err(JobError::TooLarge)
        );
        assert_eq!(
            Job::Line { dx: 1.0, dy: 0.0 }.planned([i32::MAX - 10, 0, 0], &cfg()),
            Err(JobError::TooLarge)
        );
    }

    #[test]
    fn star_table_is_libms_cos_and_sin_of_the_star_angles() {
        for (k, [c, s]) in STAR.iter().enumerate() {
            let a = PI / 2.0 - (k as f32) * (4.0 * PI / 5.0);
            assert_eq!(c.to_bits(), libm::cosf(a).to_bits(), "cos {k}");
            assert_eq!(s.to_bits(), libm::sinf(a).to_bits(), "sin {k}");
        }
    }

    #[test]
    fn preview_points_start_at_zero_and_follow_the_shape() {
        let e = Job::Ellipse { a: 20.0, b: 10.0 };
        assert_eq!(e.point_at(0.0), [0.0, 0.0]);
        let (lo, hi) = e.bounds();
        assert!((lo[0] + 40.0).abs() < 0.01 && hi[0].abs() < 0.01);
        assert!((lo[1] + 10.0).abs() < 0.01 && (hi[1] - 10.0).abs() < 0.01);
        let top = Job::Arc {
            r: 10.0,
            theta: 90.0,
        }
        .point_at(1.0);
        assert!((top[0] + 10.0).abs() < 1e-4 && (top[1] - 10.0).abs() < 1e-4);
    }
}
