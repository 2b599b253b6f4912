//! Arc geometry for G2/G3: the centre and sweep from the I/J or R words (with Grbl's
//! tolerance for end points that CAM rounding moved off the circle), the arc as a path
//! in step space (a circle, or the ellipse it becomes with unequal X/Y resolution),
//! and the points that bound its extent for the travel checks.

use super::parser::WordBlock;
use super::units::{
    mm_between, mm_to_nm, nm_to_fine_steps, nm_to_mm, nm_to_steps, value_to_nm, Nm, NmPos, Reach,
};
use super::ErrorCode;
use crate::fmath;
use crate::motion::Path;
use crate::settings::Settings;
use core::f32::consts::{FRAC_PI_2, TAU};

/// Grbl's tolerance for arc end points that CAM rounding moved off the circle.
const ARC_ABS_TOL: f32 = 0.005;
const ARC_MAX_ERR: f32 = 0.5;
const ARC_REL_TOL: f32 = 0.001;

/// A G2/G3 arc in the XY plane.
pub(super) struct ArcGeom {
    /// Centre, absolute machine nanometres (X, Y): exact for the I/J form.
    pub(super) center: [Nm; 2],
    /// Radius, mm.
    pub(super) radius: f32,
    pub(super) start_angle: f32,
    /// Swept angle, > 0, in the arc's direction.
    pub(super) sweep: f32,
}

/// Normalise an angle difference into (0, 2*pi].
fn positive_sweep(mut a: f32) -> f32 {
    while a <= 0.0 {
        a += TAU;
    }
    while a > TAU {
        a -= TAU;
    }
    a
}

/// Centre and sweep of a G2/G3 block from its I/J or R words (in block units).
pub(super) fn arc_geometry(
    b: &mut WordBlock,
    start: &NmPos,
    target: &NmPos,
    ccw: bool,
    inches: bool,
) -> Result<ArcGeom, ErrorCode> {
    let dx = mm_between(start[0], target[0]);
    let dy = mm_between(start[1], target[1]);
    // The centre relative to the start, in nanometres.
    let (ci, cj) = if let Some(r) = b.take(b'R') {
        let r = nm_to_mm(value_to_nm(r, inches));
        if dx == 0.0 && dy == 0.0 {
            return Err(ErrorCode::InvalidTarget);
        }
        let mut disc = 4.0 * r * r - dx * dx - dy * dy;
        if disc < 0.0 {
            // A half circle with a rounded radius: accept within the tolerance.
            let chord = fmath::hypot(dx, dy);
            if chord / 2.0 - fmath::abs(r) > ARC_ABS_TOL {
                return Err(ErrorCode::ArcRadiusError);
            }
            disc = 0.0;
        }
        // Offset of the centre from the chord midpoint, as a multiple of the chord
        // turned by 90 degrees; its sign picks the side (G2 with positive R: right).
        let mut h = -fmath::sqrt(disc) / fmath::hypot(dx, dy);
        if ccw {
            h = -h;
        }
        if r < 0.0 {
            h = -h;
        }
        (mm_to_nm(0.5 * (dx - dy * h)), mm_to_nm(0.5 * (dy + dx * h)))
    } else {
        let i = b.take(b'I').map(|v| value_to_nm(v, inches));
        let j = b.take(b'J').map(|v| value_to_nm(v, inches));
        if i.is_none() && j.is_none() {
            return Err(ErrorCode::NoOffsetsInPlane);
        }
        (i.unwrap_or(0), j.unwrap_or(0))
    };
    if b.get(b'K').is_some() {
        return Err(ErrorCode::UnusedWords);
    }
    let center = [start[0].saturating_add(ci), start[1].saturating_add(cj)];
    let (ci, cj) = (nm_to_mm(ci), nm_to_mm(cj));
    let r_start = fmath::hypot(ci, cj);
    let r_end = fmath::hypot(
        mm_between(center[0], target[0]),
        mm_between(center[1], target[1]),
    );
    let dr = fmath::abs(r_end - r_start);
    if !r_start.is_finite()
        || !r_end.is_finite()
        || r_start <= 0.0
        || (dr > ARC_ABS_TOL && (dr > ARC_MAX_ERR || dr > ARC_REL_TOL * r_start))
    {
        return Err(ErrorCode::InvalidTarget);
    }
    let a0 = fmath::atan2(-cj, -ci);
    let a1 = fmath::atan2(
        mm_between(center[1], target[1]),
        mm_between(center[0], target[0]),
    );
    let same_point = dx == 0.0 && dy == 0.0;
    let sweep = if same_point {
        TAU
    } else if ccw {
        positive_sweep(a1 - a0)
    } else {
        positive_sweep(a0 - a1)
    };
    Ok(ArcGeom {
        center,
        radius: r_start,
        start_angle: a0,
        sweep,
    })
}

/// The arc in step space: a circle if X and Y have the same resolution, else the
/// ellipse the circle becomes. A circle keeps its exact start and centre in 1/256 step
/// (`Path::ArcFine`: every step on the grid point nearest the programmed circle, wherever
/// its centre falls between steps); beyond that range (2^22 steps) the centre is rounded
/// to a step. The caller has checked that start and extremes are in range, so the
/// conversions to whole steps do not fail (0 if they did).
pub(super) fn arc_path(g: &ArcGeom, start: &NmPos, ccw: bool, s: &Settings) -> Path {
    let sx = s.steps_per_mm(0);
    let sy = s.steps_per_mm(1);
    let steps = |nm, spm| nm_to_steps(nm, spm).unwrap_or(0);
    let center = [
        steps(g.center[0], sx).saturating_sub(steps(start[0], sx)),
        steps(g.center[1], sy).saturating_sub(steps(start[1], sy)),
    ];
    if sx != sy {
        let radius = mm_to_nm(g.radius);
        return Path::Ellipse {
            center,
            a: steps(radius, sx),
            b: steps(radius, sy),
            ccw,
        };
    }
    let fine = |nm| nm_to_fine_steps(nm, sx);
    match (
        fine(start[0]),
        fine(start[1]),
        fine(g.center[0]),
        fine(g.center[1]),
    ) {
        (Some(fx), Some(fy), Some(cx), Some(cy)) => Path::ArcFine {
            from: [fx, fy],
            center: [cx, cy],
            ccw,
            turns: 0,
        },
        _ => Path::Arc {
            center,
            ccw,
            turns: 0,
        },
    }
}

/// Check the points that bound the arc: its end and every axis extreme it passes.
pub(super) fn arc_extremes(
    g: &ArcGeom,
    start: &NmPos,
    target: &NmPos,
    ccw: bool,
    pts: &mut Reach,
    s: &Settings,
) {
    pts.add(target, s);
    // cos and sin of k * 90 degrees, without pulling sinf/cosf into the image.
    let axes_dirs = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)];
    for (k, &(cs, sn)) in axes_dirs.iter().enumerate() {
        let angle = k as f32 * FRAC_PI_2;
        let from_start = if ccw {
            positive_sweep(angle - g.start_angle)
        } else {
            positive_sweep(g.start_angle - angle)
        };
        if from_start <= g.sweep || g.sweep >= TAU - 1e-6 {
            // The sweep is positive (`positive_sweep`, or a full turn).
            let frac = (from_start / g.sweep).min(1.0);
            let z = start[2].saturating_add(mm_to_nm(mm_between(start[2], target[2]) * frac));
            pts.add(
                &[
                    g.center[0].saturating_add(mm_to_nm(g.radius * cs)),
                    g.center[1].saturating_add(mm_to_nm(g.radius * sn)),
                    z,
                ],
                s,
            );
        }
    }
}
