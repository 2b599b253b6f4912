//! Polylines built from straight moves, starting with the lab report's continuous
//! five-pointed star ({5/2}: every second vertex of a regular pentagon).
//!
//! Owns only vertex geometry in step space; the caller turns vertices into
//! [`crate::motion::Move`]s with the feed it wants.

use crate::decimal::round_i32;
use crate::motion::StepPos;

/// The six vertices (the last equals the first) of a {5/2} star inscribed in a circle
/// of radius `r` steps centred at `center`, first vertex straight up, drawn in one
/// continuous stroke. Vertices are rounded to the nearest step.
pub fn star(center: [i32; 2], r: i32, z: i32) -> [StepPos; 6] {
    let mut v = [[0i32; 3]; 6];
    for (i, p) in v.iter_mut().enumerate() {
        let k = (2 * i) % 5;
        let ang = core::f32::consts::FRAC_PI_2 + core::f32::consts::TAU * k as f32 / 5.0;
        let (sin, cos) = crate::fmath::sin_cos(ang);
        let x = center[0] as f32 + r as f32 * cos;
        let y = center[1] as f32 + r as f32 * sin;
        *p = [round_i32(x), round_i32(y), z];
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interpolation::{line::DdaLine, Interpolate};

    #[test]
    fn star_is_closed_and_every_edge_interpolates_to_its_vertex() {
        let v = star([0, 0], 3200, 0);
        assert_eq!(v[0], v[5]);
        assert_eq!(v[0], [0, 3200, 0]);
        let mut p = v[0];
        for w in v.windows(2) {
            let mut l = DdaLine::new(w[0], w[1]);
            while let Some(t) = l.next_event() {
                t.apply(&mut p);
            }
            assert_eq!(p, w[1]);
        }
        // Edges of a {5/2} star all have the same length (chord over 144 degrees).
        let len = |a: StepPos, b: StepPos| f64::from(a[0] - b[0]).hypot(f64::from(a[1] - b[1]));
        let l0 = len(v[0], v[1]);
        assert!((l0 - 2.0 * 3200.0 * (72f64).to_radians().sin()).abs() < 2.0);
        for w in v.windows(2) {
            assert!((len(w[0], w[1]) - l0).abs() < 2.0);
        }
    }
}
