//! Machine millimetres and steps: the conversions (rounded half away from zero, so
//! rounding never accumulates), the step range a target must stay in, and the travel
//! limits that soft limits check.

use crate::decimal::round_i32;
use crate::fmath;
use crate::motion::{StepPos, AXES};
use crate::settings::Settings;

/// mm to steps for one axis, rounding half away from zero (saturating).
#[inline(never)]
pub fn mm_to_steps(mm: f32, steps_per_mm: f32) -> i32 {
    round_i32(mm * steps_per_mm)
}

/// Machine mm to a step position.
pub fn to_steps(mm: &[f32; AXES], s: &Settings) -> StepPos {
    let mut out = [0; AXES];
    for (axis, o) in out.iter_mut().enumerate() {
        *o = mm_to_steps(mm.get(axis).copied().unwrap_or(0.0), s.steps_per_mm(axis));
    }
    out
}

/// Step position to machine mm.
pub fn to_mm(steps: &StepPos, s: &Settings) -> [f32; AXES] {
    let mut out = [0.0; AXES];
    for (axis, o) in out.iter_mut().enumerate() {
        *o = steps.get(axis).copied().unwrap_or(0) as f32 / s.steps_per_mm(axis);
    }
    out
}

/// Largest step coordinate accepted (2^30): leaves headroom for the planner's
/// differences and sums in `i32`.
pub const MAX_STEPS: f32 = 1_073_741_824.0;

/// True if `p` (machine mm) converts to steps without leaving the safe range.
pub fn in_step_range(p: &[f32; AXES], s: &Settings) -> bool {
    p.iter()
        .enumerate()
        .all(|(axis, &v)| fmath::abs(v * s.steps_per_mm(axis)) < MAX_STEPS)
}

/// Allowed machine range of `axis` with soft limits, or `None` if unchecked.
/// Axes homed toward - live in [0, travel], axes homed toward + in [-travel, 0]
/// (Grbl's convention); axes without a switch ($214) are not checked.
pub fn travel_range(axis: usize, s: &Settings) -> Option<(f32, f32)> {
    let bit = 1u8 << axis;
    if s.switch_mask() & bit == 0 {
        return None;
    }
    let t = s.max_travel(axis);
    Some(if s.homing_dir_mask() & bit != 0 {
        (0.0, t)
    } else {
        (-t, 0.0)
    })
}

/// True if `p` (machine mm) lies within travel on every checked axis.
pub fn within_travel(p: &[f32; AXES], s: &Settings) -> bool {
    const EPS: f32 = 1e-4;
    let (switches, toward_minus) = (s.switch_mask(), s.homing_dir_mask());
    p.iter().enumerate().all(|(axis, &v)| {
        let bit = 1u8 << axis;
        // Mirrored onto [0, travel] (negation is exact, so the bounds are the same).
        let v = if toward_minus & bit != 0 { v } else { -v };
        switches & bit == 0 || (v >= -EPS && v <= s.max_travel(axis) + EPS)
    })
}

/// Every point a block moves to, checked as it is planned; the verdicts are reported
/// after the block's word checks, in Grbl's order.
pub(super) struct Reach {
    /// All points convert to steps ([`in_step_range`]).
    pub(super) in_range: bool,
    /// All points lie within travel ([`within_travel`]).
    pub(super) in_travel: bool,
}

impl Reach {
    pub(super) fn add(&mut self, p: &[f32; AXES], s: &Settings) {
        self.in_range &= in_step_range(p, s);
        self.in_travel &= within_travel(p, s);
    }
}
