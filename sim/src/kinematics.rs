//! Speeds and accelerations recovered from a step trace, for plots.
//!
//! Each axis's position is taken as the piecewise-linear curve through its step events
//! (time, position after the step); the half-step offset of a stepped staircase cancels
//! in the differences. Velocity and acceleration are central differences of that curve
//! over short windows, sampled on a regular grid.

use crate::trace::Trace;

/// Samples of the motion on a regular time grid.
#[derive(Clone, Debug, Default)]
pub struct Kinematics {
    pub t_s: Vec<f64>,
    /// Path speed in the XY plane, mm/s.
    pub speed: Vec<f64>,
    /// Per-axis velocity and acceleration, mm/s and mm/s^2.
    pub vel: [Vec<f64>; 3],
    pub acc: [Vec<f64>; 3],
}

/// One axis as (time s, position steps) knots, starting at rest at t = 0.
fn knots(trace: &Trace, axis: usize) -> Vec<(f64, f64)> {
    let mut k = vec![(0.0, 0.0)];
    let mut last = 0;
    for r in &trace.rows {
        if r.pos[axis] != last {
            k.push((r.t_us * 1e-6, r.pos[axis] as f64));
            last = r.pos[axis];
        }
    }
    k
}

/// Position at `t` on the piecewise-linear curve (constant outside it).
fn at(k: &[(f64, f64)], t: f64) -> f64 {
    let i = k.partition_point(|&(tk, _)| tk <= t);
    if i == 0 {
        return k[0].1;
    }
    if i == k.len() {
        return k[k.len() - 1].1;
    }
    let (t0, p0) = k[i - 1];
    let (t1, p1) = k[i];
    p0 + (p1 - p0) * (t - t0) / (t1 - t0)
}

/// Samples every `dt` seconds; velocity from central differences over `h` seconds,
/// acceleration over `h_acc` (longer: the minor axis of a DDA line steps on the major
/// axis's ticks, and that timing jitter grows with 1/h^2 in a second difference).
pub fn from_trace(
    trace: &Trace,
    steps_per_mm: [f64; 3],
    dt: f64,
    h: f64,
    h_acc: f64,
) -> Kinematics {
    let end = trace.rows.last().map_or(0.0, |r| r.t_us * 1e-6);
    let ks: Vec<Vec<(f64, f64)>> = (0..3).map(|a| knots(trace, a)).collect();
    let mut out = Kinematics::default();
    let n = (end / dt).ceil() as usize + 1;
    for i in 0..n {
        let t = i as f64 * dt;
        let mut v = [0.0; 3];
        for a in 0..3 {
            let x = |tt: f64| at(&ks[a], tt) / steps_per_mm[a];
            v[a] = (x(t + h) - x(t - h)) / (2.0 * h);
            out.vel[a].push(v[a]);
            out.acc[a].push((x(t + h_acc) - 2.0 * x(t) + x(t - h_acc)) / (h_acc * h_acc));
        }
        out.speed.push(v[0].hypot(v[1]));
        out.t_s.push(t);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::Row;

    /// A trace of one axis under constant acceleration `a` steps/s^2 from rest.
    fn accelerating(a: f64, steps: i32) -> Trace {
        let rows = (1..=steps)
            .map(|n| Row {
                t_us: (2.0 * n as f64 / a).sqrt() * 1e6,
                pos: [n, 0, 0],
            })
            .collect();
        Trace { rows }
    }

    #[test]
    fn recovers_constant_acceleration() {
        // 500 mm/s^2 at 80 steps/mm.
        let t = accelerating(40_000.0, 4000);
        let k = from_trace(&t, [80.0; 3], 0.001, 0.005, 0.01);
        // Away from the start and end, acceleration and speed are close to the truth.
        for (i, &ts) in k.t_s.iter().enumerate() {
            if (0.05..0.40).contains(&ts) {
                assert!(
                    (k.acc[0][i] - 500.0).abs() < 10.0,
                    "a({ts}) = {}",
                    k.acc[0][i]
                );
                assert!(
                    (k.speed[i] - 500.0 * ts).abs() < 1.0,
                    "v({ts}) = {}",
                    k.speed[i]
                );
            }
        }
        assert!(k.acc[1].iter().all(|&a| a == 0.0));
    }

    #[test]
    fn interpolation() {
        let k = vec![(0.0, 0.0), (1.0, 2.0), (2.0, 2.0)];
        assert_eq!(at(&k, -1.0), 0.0);
        assert_eq!(at(&k, 0.5), 1.0);
        assert_eq!(at(&k, 1.5), 2.0);
        assert_eq!(at(&k, 3.0), 2.0);
    }
}
