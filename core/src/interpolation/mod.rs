//! Exact interpolation in integer step space: turns one move into a sequence of
//! [`StepEvent`]s, each moving every axis by at most one step.
//!
//! Owns the geometry of step sequences and nothing about time: the step engine
//! decides when each step event happens. Every interpolator is a small state machine that
//! yields one step event per call, so the segment preparation task can pull exactly as many
//! step events as fit into its queue, with no allocation and no look-ahead buffer.
//!
//! Two methods, as in the lab report (seed 000, 3.5-3.8) and common CNC practice:
//! - [`Method::Classic`]: point-by-point comparison, one axis per step event, within 1 step.
//! - [`Method::Dda`]: axes may step together; every step event lands on the grid point
//!   nearest the ideal path (per-axis error <= 0.5 step).
//!
//! Submodules: [`line`](mod@line) (straight lines), [`circle`] (circles and arcs around any
//! centre), [`conic`] (axis-aligned ellipses), [`curve`] (y = f(x), e.g. the sine),
//! [`shapes`] (polylines such as the star).
//!
//! For the step timing, each interpolator tells what comes next ([`Next`]): a run of
//! step events along which the path position is a smooth function of the step event count (lines,
//! DDA circle octants: [`Interpolator::path_ahead`]), which the segment preparation times with
//! a few polynomials; a step event whose length is known once it is made (ellipses, sines,
//! classic circles: [`Interpolator::tick_len`]); or an extra step onto the grid point nearest
//! the path (a rounded start or end), which takes no path length.

pub mod circle;
pub mod conic;
pub mod curve;
pub mod line;
pub mod shapes;

use crate::motion::{Move, Path, StepPos, AXES, X, Y, Z};

/// One interpolation step event: which axes step (bits 0..2 = X, Y, Z) and in which
/// direction (bits 3..5 set = negative). Packed in a byte so the step queue is small.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepEvent(pub u8);

impl StepEvent {
    /// Builds a step event from per-axis deltas in {-1, 0, 1} (bit operations only: this
    /// runs once per step in the segment preparation).
    #[inline]
    pub fn from_deltas(d: [i8; AXES]) -> Self {
        let bit = |v: i8, i: u8| -> u8 { (u8::from(v != 0) << i) | (u8::from(v < 0) << (i + 3)) };
        StepEvent(bit(d[0], 0) | bit(d[1], 1) | bit(d[2], 2))
    }
    /// Step mask (bit i = axis i steps).
    pub const fn steps(self) -> u8 {
        self.0 & 0b111
    }
    /// Direction mask (bit i = axis i moves negative); only meaningful where stepping.
    pub const fn dirs(self) -> u8 {
        (self.0 >> 3) & 0b111
    }
    /// Per-axis deltas in {-1, 0, 1}.
    #[inline]
    pub fn deltas(self) -> [i8; AXES] {
        let d = |i: u8| -> i8 {
            let step = (self.0 >> i) & 1;
            let neg = (self.0 >> (i + 3)) & 1;
            (step as i8) * (1 - 2 * neg as i8)
        };
        [d(0), d(1), d(2)]
    }
    /// Applies the step event to a position (wrapping at the i32 range, never panics).
    #[inline]
    pub fn apply(self, p: &mut StepPos) {
        let d = self.deltas();
        p[0] = p[0].wrapping_add(i32::from(d[0]));
        p[1] = p[1].wrapping_add(i32::from(d[1]));
        p[2] = p[2].wrapping_add(i32::from(d[2]));
    }
}

/// Interpolation method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Method {
    /// Point-by-point comparison: one axis per step event (the lab report's method).
    Classic,
    /// Digital differential analyser / Bresenham: axes may step together, each step event on
    /// the grid point nearest the path.
    #[default]
    Dda,
}

/// Why a move cannot be interpolated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InterpError {
    /// Radius, semi-axis or coordinates outside what exact integer math supports.
    TooLarge,
    /// Degenerate geometry (zero radius or semi-axis, non-finite curve parameters).
    Degenerate,
    /// The curve is planar (XY) but the target changes Z.
    NotPlanar,
}

/// What an interpolator makes next (see the module comment).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// This many step events, each advancing the run's parameter by one: the path position is
    /// [`Interpolator::path_ahead`] of the step event count.
    Run(u32),
    /// One step event whose path length [`Interpolator::tick_len`] gives after it is made.
    StepEvent,
    /// One step event onto the grid point nearest the path or onto the target: no path length.
    Extra,
    /// The move is complete.
    Done,
}

/// Something that yields step events until the move is complete.
pub trait Interpolate {
    /// The next step event, or `None` when the end position has been reached.
    fn next_event(&mut self) -> Option<StepEvent>;
}

/// Any interpolator for a [`Move`], chosen from its [`Path`].
#[derive(Clone, Debug)]
pub enum Interpolator {
    Line(line::Line),
    Circle(circle::Circle),
    Conic(conic::Conic),
    Sine(curve::CurveTrace<curve::Sine>),
}

impl Interpolator {
    /// Interpolator for `mv`, starting from `start`.
    // Out of line: inlined into the preparation's `start_next`, LLVM moved each
    // variant's fields one by one through that frame's temporaries (hundreds of bytes
    // of loads and stores); here the result is written once, through the return slot.
    #[inline(never)]
    pub fn new(start: StepPos, mv: &Move, method: Method) -> Result<Self, InterpError> {
        // Everything but a plain line is planar (XY): one check for all of them.
        if !matches!(mv.path, Path::Line) {
            planar(start, mv.target)?;
        }
        let at = |v: i32| i64::from(v) * 256;
        match mv.path {
            Path::Line => Ok(Interpolator::Line(line::Line::new(
                start, mv.target, method,
            ))),
            Path::LineFine { from, to } => Ok(Interpolator::Line(
                match (method, line::FineLine::new(start, mv.target, from, to)) {
                    (Method::Dda, Some(l)) => line::Line::Fine(l),
                    _ => line::Line::new(start, mv.target, method),
                },
            )),
            Path::Arc { center, ccw, turns } => {
                let from = [at(start[X]), at(start[Y])];
                let c = [at(start[X] + center[0]), at(start[Y] + center[1])];
                circle::Circle::new(start, from, c, mv.target, ccw, turns, method)
                    .map(Interpolator::Circle)
            }
            Path::ArcFine {
                from,
                center,
                ccw,
                turns,
            } => {
                let from = [i64::from(from[0]), i64::from(from[1])];
                let c = [i64::from(center[0]), i64::from(center[1])];
                circle::Circle::new(start, from, c, mv.target, ccw, turns, method)
                    .map(Interpolator::Circle)
            }
            Path::Ellipse { center, a, b, ccw } => {
                conic::Conic::ellipse(start, center, a, b, mv.target, ccw, method)
                    .map(Interpolator::Conic)
            }
            Path::Sine { amp, omega, phase } => {
                let c = curve::Sine::new(amp, omega, phase)?;
                Ok(Interpolator::Sine(curve::CurveTrace::new(
                    start, mv.target, c, method,
                )))
            }
        }
    }

    /// What comes next (moving a circle on to its next piece when one is used up).
    /// Not an iterator: it never ends, it says [`Next::Done`].
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Next {
        match self {
            Interpolator::Line(l) => l.next(),
            Interpolator::Circle(c) => c.next(),
            // Known only once tried: `events_into` returns 0 at the end.
            Interpolator::Conic(_) | Interpolator::Sine(_) => Next::StepEvent,
        }
    }

    /// Up to `out.len()` step events of what [`Interpolator::next`] announced (one for a single
    /// step event); the count written, 0 when the move is complete.
    pub fn events_into(&mut self, out: &mut [StepEvent]) -> usize {
        match self {
            Interpolator::Line(l) => l.events_into(out),
            Interpolator::Circle(c) => c.ticks(out),
            Interpolator::Conic(c) => line::fill(c, out.get_mut(..1).unwrap_or(&mut [])),
            Interpolator::Sine(c) => line::fill(c, out.get_mut(..1).unwrap_or(&mut [])),
        }
    }

    /// Path position `k` step events ahead in the present run, relative to the present point,
    /// and its rate per step event there, in run units (a line's step event; a circle's step).
    pub fn path_ahead(&self, k: u32) -> (f32, f32) {
        match self {
            Interpolator::Circle(c) => c.path_ahead(k),
            _ => (k as f32, 1.0),
        }
    }

    /// Largest |d^n s / dk^n| (n = 1..4) of the path position over the next `k` step events
    /// of the present run, in run units: what bounds the timing polynomials' error.
    pub fn run_bounds(&self, k: u32) -> [f32; 4] {
        match self {
            Interpolator::Circle(c) => c.run_bounds(k),
            _ => [1.0, 0.0, 0.0, 0.0],
        }
    }

    /// Path position where the present run (just begun) starts, less where the run
    /// before it ended, in run units: a circle's pieces measure the same point by
    /// different coordinates ([`circle::Circle::entry_shift`]).
    pub fn entry_shift(&self) -> f32 {
        match self {
            Interpolator::Circle(c) => c.entry_shift(),
            _ => 0.0,
        }
    }

    /// The present run ends the path (whose length is then known exactly): an arc's
    /// last piece. A line is one run from the start.
    pub fn in_last_run(&self) -> bool {
        match self {
            Interpolator::Circle(c) => c.in_last_piece(),
            _ => false,
        }
    }

    /// Path length of the last step event (after [`Next::StepEvent`]), mm, from the axes'
    /// steps per mm.
    pub fn tick_len(&self, steps_per_mm: [f32; 2]) -> f32 {
        let [spx, spy] = steps_per_mm;
        match self {
            Interpolator::Circle(c) => c.last_tick_len() / spx,
            Interpolator::Conic(c) => c.last_tick_len(spx, spy),
            Interpolator::Sine(c) => c.tick_len(spx, spy),
            Interpolator::Line(_) => 0.0,
        }
    }
}

impl Interpolate for Interpolator {
    fn next_event(&mut self) -> Option<StepEvent> {
        let mut one = [StepEvent(0)];
        (self.events_into(&mut one) == 1).then_some(one[0])
    }
}

fn planar(start: StepPos, target: StepPos) -> Result<(), InterpError> {
    if start[Z] == target[Z] {
        Ok(())
    } else {
        Err(InterpError::NotPlanar)
    }
}

/// Sign of an i64 as -1, 0 or 1.
pub(crate) fn sgn(v: i64) -> i8 {
    i8::from(v > 0) - i8::from(v < 0)
}

/// XY deltas to a step event with no Z motion.
pub(crate) fn event_xy(dx: i8, dy: i8) -> StepEvent {
    let mut d = [0i8; AXES];
    d[X] = dx;
    d[Y] = dy;
    StepEvent::from_deltas(d)
}
