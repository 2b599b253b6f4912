//! The motion contract: what producers (G-code interpreter, keypad modes) hand to the
//! planner, move by move ([`Move`]) and as queue entries ([`Command`]: moves, dwells,
//! servo pen lifts). Everything is in integer step space so that interpolation is exact; the
//! planner converts rates and accelerations with the settings' steps/mm.
//!
//! Kept tiny and stable on purpose: several modules depend on these types.
//!
//! Range: moves start and end within +-[`POS_LIMIT`] steps on every axis (13 km at
//! 80 steps/mm); the planner rejects any other move as invalid, so the interpolators'
//! counters stay 32-bit (a line between any two points of the range is exact; a sine
//! is limited to an amplitude of 2^28 steps). Nothing panics outside the range, the
//! ticks are then just not meaningful.

/// Number of axes: X, Y and Z (the pen).
pub const AXES: usize = 3;
/// Axis indices into [`StepPos`].
pub const X: usize = 0;
pub const Y: usize = 1;
pub const Z: usize = 2;

/// An absolute machine position in steps.
pub type StepPos = [i32; AXES];

/// Moves start and end strictly inside +-POS_LIMIT steps on every axis (2^30): a
/// line's travel is then below 2^31 steps, which the interpolators count in u32.
pub const POS_LIMIT: u32 = 1 << 30;

/// The shape of one move, from the current position to [`Move::target`], in step space.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Path {
    /// A straight line (X, Y and Z together).
    Line,
    /// A straight XY line whose ideal end points lie between steps (G-code targets in
    /// mm rarely fall on a step): `from` and `to` are the exact start and end in 1/256
    /// step, absolute. Every step lands on the grid point nearest this ideal line, not
    /// the line between the rounded ends; `target` must be `to` rounded (Z unchanged).
    LineFine { from: [i32; 2], to: [i32; 2] },
    /// A circular arc in the XY plane. `center` is relative to the start point, in steps.
    /// `turns` counts extra full turns (a full circle is `target == start`, `turns = 0`
    /// is interpreted by the planner as one whole revolution, as G2/G3 do).
    Arc {
        center: [i32; 2],
        ccw: bool,
        turns: u16,
    },
    /// A circular arc in the XY plane around a centre that may lie between steps (G-code
    /// I/J in mm, the R form, inch units): `from` is the exact start and `center` the
    /// centre, absolute, in 1/256 step; the arc runs on the circle around `center`
    /// through `from`, to `target` (the exact end rounded). `turns` as for [`Path::Arc`].
    /// Every step lands on the grid point nearest this circle.
    ArcFine {
        from: [i32; 2],
        center: [i32; 2],
        ccw: bool,
        turns: u16,
    },
    /// An axis-aligned elliptical arc in the XY plane: semi-axes `a` (X) and `b` (Y) in
    /// steps, `center` relative to the start point (which must lie on the ellipse).
    Ellipse {
        center: [i32; 2],
        a: i32,
        b: i32,
        ccw: bool,
    },
    /// y = amp * sin(omega * u + phase) - amp * sin(phase), with u = x - x_start in
    /// steps; the curve starts at the current position and runs to `target` X.
    /// Units: `amp` in steps, `omega` in radians per step, `phase` in radians.
    Sine { amp: f32, omega: f32, phase: f32 },
}

/// How fast a move runs.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Feed {
    /// As fast as the axis limits allow (G0).
    Rapid,
    /// Path speed in mm/min (G1/G2/G3 with G94).
    MmPerMin(f32),
}

/// One planner input.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Move {
    /// Absolute end position in steps.
    pub target: StepPos,
    pub path: Path,
    pub feed: Feed,
    /// Source line number (G-code N word or stream line), for reports. 0 if none.
    pub line: u32,
}

/// The pen level of a pen fully down ([`Command::Pen`]); 0 is up.
pub const PEN_FULL: u16 = 1000;

/// One entry of the planner queue.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Move along a path.
    Move(Move),
    /// Wait `ms` milliseconds at rest (G4), after the moves before it have finished.
    Dwell { ms: u32 },
    /// Turn the RC-servo pen to `level` (0 = up, [`PEN_FULL`] = fully down, between:
    /// `M3 S`), at rest: at the servo speed ($208), then the lift ($204) or drop ($207)
    /// time. Only used when the pen is a servo ($201 = 1); with a Z-axis pen the
    /// interpreter queues Z moves instead.
    Pen { level: u16 },
}
