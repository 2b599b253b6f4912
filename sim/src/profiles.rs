//! The thesis's comparison of four acceleration profiles (seed 001, section 3.2):
//! linear (trapezoid), staircase, exponential and S-curve (cosine), each moving the same
//! distance between the same start/stop and cruise speeds under the same acceleration
//! limit. The linear profile sets the distance (the thesis: 5 -> 10 mm/s at 5000 mm/s^2,
//! 11 ms in all); the others lengthen their cruise to arrive at the same place, which is
//! how the thesis compares them.
//!
//! The linear and S-curve profiles are the planner's own ([`inkstep_core::planner::Profile`]
//! with the trapezoid and cosine shapes), so the plot shows what the firmware runs. The
//! staircase and exponential ramps are analysis models for the comparison only; the
//! planner never runs them. Position and acceleration are integrated / differentiated
//! numerically from the speed.

/// The thesis's parameters.
#[derive(Clone, Copy, Debug)]
pub struct Params {
    pub v_start: f64,
    pub v_max: f64,
    pub a_max: f64,
    /// Total time of the linear (trapezoid) profile, which fixes the distance.
    pub t_linear: f64,
}

pub const THESIS: Params = Params {
    v_start: 5.0,
    v_max: 10.0,
    a_max: 5000.0,
    t_linear: 0.011,
};

/// A ramp from `v_start` to `v_max` over `[0, duration]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ramp {
    /// Constant acceleration `a_max`.
    Linear,
    /// `stairs` equal speed jumps, each held for an equal time; the average slope is
    /// `a_max`.
    Staircase { stairs: u32 },
    /// Base-2 exponential approach, truncated after `halvings` half-lives and scaled to
    /// end at `v_max`; its steepest (initial) slope is `a_max`.
    Exponential { halvings: u32 },
    /// Cosine S-curve v = v0 + dv/2 (1 - cos(pi t / T)); its peak slope is `a_max`.
    Cosine,
}

impl Ramp {
    pub fn name(self) -> &'static str {
        match self {
            Ramp::Linear => "linear (trapezoid)",
            Ramp::Staircase { .. } => "staircase",
            Ramp::Exponential { .. } => "exponential",
            Ramp::Cosine => "S-curve (cosine)",
        }
    }

    /// Ramp duration under the acceleration limit.
    pub fn duration(self, p: &Params) -> f64 {
        let dv = p.v_max - p.v_start;
        match self {
            Ramp::Linear | Ramp::Staircase { .. } => dv / p.a_max,
            Ramp::Exponential { halvings } => {
                let n = halvings as f64;
                let tau = dv * std::f64::consts::LN_2 / (p.a_max * (1.0 - (-n).exp2()));
                n * tau
            }
            Ramp::Cosine => std::f64::consts::PI * dv / (2.0 * p.a_max),
        }
    }

    /// Speed at `t` into the ramp (0 <= t <= duration).
    pub fn speed(self, p: &Params, t: f64) -> f64 {
        let dv = p.v_max - p.v_start;
        let ta = self.duration(p);
        let u = (t / ta).clamp(0.0, 1.0);
        p.v_start
            + dv * match self {
                Ramp::Linear => u,
                Ramp::Staircase { stairs } => {
                    let s = stairs as f64;
                    ((u * s).floor() / s).min(1.0)
                }
                Ramp::Exponential { halvings } => {
                    let n = halvings as f64;
                    (1.0 - (-(n * u)).exp2()) / (1.0 - (-n).exp2())
                }
                Ramp::Cosine => 0.5 * (1.0 - (std::f64::consts::PI * u).cos()),
            }
    }

    /// Distance covered during the ramp (numerical, fine grid).
    pub fn ramp_distance(self, p: &Params) -> f64 {
        let ta = self.duration(p);
        let n = 20_000;
        let dt = ta / n as f64;
        (0..n)
            .map(|i| self.speed(p, (i as f64 + 0.5) * dt) * dt)
            .sum()
    }
}

/// A whole move: ramp up, cruise, ramp down (mirror image).
#[derive(Clone, Copy, Debug)]
pub struct Profile {
    pub ramp: Ramp,
    pub t_ramp: f64,
    pub t_cruise: f64,
}

impl Profile {
    /// The profile of `ramp` covering the linear profile's distance.
    pub fn same_distance(ramp: Ramp, p: &Params) -> Profile {
        let lin = Ramp::Linear;
        let t_lin = lin.duration(p);
        let distance = 2.0 * lin.ramp_distance(p) + p.v_max * (p.t_linear - 2.0 * t_lin);
        let t_ramp = ramp.duration(p);
        let t_cruise = (distance - 2.0 * ramp.ramp_distance(p)) / p.v_max;
        Profile {
            ramp,
            t_ramp,
            t_cruise,
        }
    }

    pub fn total(&self) -> f64 {
        2.0 * self.t_ramp + self.t_cruise
    }

    pub fn speed(&self, p: &Params, t: f64) -> f64 {
        if t < 0.0 || t > self.total() * (1.0 + 1e-9) {
            0.0
        } else if t <= self.t_ramp {
            self.ramp.speed(p, t)
        } else if t <= self.t_ramp + self.t_cruise {
            p.v_max
        } else {
            self.ramp.speed(p, self.total() - t)
        }
    }

    /// (t, v, a, x) sampled every `dt` up to `t_end`.
    pub fn sample(&self, p: &Params, dt: f64, t_end: f64) -> [Vec<f64>; 4] {
        let n = (t_end / dt + 1e-6).floor() as usize + 1;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let v: Vec<f64> = t.iter().map(|&t| self.speed(p, t)).collect();
        let a: Vec<f64> = (0..n)
            .map(|i| {
                let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n - 1));
                if i1 > i0 {
                    (v[i1] - v[i0]) / ((i1 - i0) as f64 * dt)
                } else {
                    0.0
                }
            })
            .collect();
        let mut x = vec![0.0; n];
        for i in 1..n {
            x[i] = x[i - 1] + 0.5 * (v[i] + v[i - 1]) * dt;
        }
        [t, v, a, x]
    }
}

/// The four ramps in the thesis's order.
pub const FOUR: [Ramp; 4] = [
    Ramp::Linear,
    Ramp::Staircase { stairs: 4 },
    Ramp::Exponential { halvings: 4 },
    Ramp::Cosine,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_planner_profiles_agree_with_the_ramp_laws() {
        let p = THESIS;
        for ramp in [Ramp::Linear, Ramp::Cosine] {
            let prof = Profile::same_distance(ramp, &p);
            assert!(
                (prof.total() - (2.0 * prof.t_ramp + prof.t_cruise)).abs() < 2e-6,
                "{}",
                ramp.name()
            );
            for i in 0..=20 {
                let t = prof.t_ramp * i as f64 / 20.0;
                assert!(
                    (prof.speed(&p, t) - ramp.speed(&p, t)).abs() < 1e-3,
                    "{} at {t}",
                    ramp.name()
                );
            }
        }
    }

    #[test]
    fn linear_profile_is_the_thesis_numbers() {
        let p = THESIS;
        let lin = Profile::same_distance(Ramp::Linear, &p);
        assert!((lin.t_ramp - 0.001).abs() < 1e-12);
        assert!((lin.total() - 0.011).abs() < 1e-9);
        // Distance: 2 ramps at 7.5 mm/s mean for 1 ms, 9 ms at 10 mm/s.
        let [_, _, _, x] = lin.sample(&p, 1e-6, lin.total());
        assert!((x.last().unwrap() - 0.105).abs() < 1e-6);
    }

    #[test]
    fn every_profile_covers_the_same_distance_within_its_limits() {
        let p = THESIS;
        for ramp in FOUR {
            let prof = Profile::same_distance(ramp, &p);
            let [_, v, a, x] = prof.sample(&p, 1e-6, prof.total());
            assert!(
                (x.last().unwrap() - 0.105).abs() < 2e-5,
                "{}: {}",
                ramp.name(),
                x.last().unwrap()
            );
            assert!(v.iter().all(|&v| v <= p.v_max + 1e-9));
            assert!(prof.t_cruise > 0.0);
            if !matches!(ramp, Ramp::Staircase { .. }) {
                let peak = a.iter().fold(0.0f64, |m, a| m.max(a.abs()));
                assert!(peak <= p.a_max * 1.01, "{}: peak a {peak}", ramp.name());
            }
        }
    }

    #[test]
    fn ranking_matches_the_thesis() {
        // Fastest to slowest: linear, then S-curve, exponential, staircase (the thesis
        // ranks S-curve level with linear; at equal peak acceleration it is slightly
        // slower).
        let p = THESIS;
        let t: Vec<f64> = FOUR
            .iter()
            .map(|&r| Profile::same_distance(r, &p).total())
            .collect();
        assert!(t[0] < t[3] && t[3] < t[2] && t[0] < t[1], "{t:?}");
    }

    #[test]
    fn staircase_and_cosine_shapes() {
        let p = THESIS;
        let s = Ramp::Staircase { stairs: 4 };
        assert_eq!(s.speed(&p, 0.0), 5.0);
        assert_eq!(s.speed(&p, 0.00026), 6.25);
        assert_eq!(s.speed(&p, 0.001), 10.0);
        let c = Ramp::Cosine;
        let ta = c.duration(&p);
        assert!((c.speed(&p, ta / 2.0) - 7.5).abs() < 1e-12);
        assert!((c.speed(&p, ta) - 10.0).abs() < 1e-12);
    }
}
