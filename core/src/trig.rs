//! Small sine, cosine and arctangent for the planning code, in f64.
//!
//! libm's versions carry a general argument reduction (Payne-Hanek tables) that costs
//! over 2 KB of the Blue Pill's 64 KB; every angle here is already in a few turns, so a
//! floor-based reduction and short polynomials (error below 1e-9) are enough.

use core::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};

/// Sine and cosine of `x` (radians, any finite value of moderate size).
pub fn sin_cos(x: f64) -> (f64, f64) {
    // Reduce to [-pi, pi], then to [-pi/2, pi/2] with sin(pi - r) = sin r.
    let mut r = x - libm::floor(x / TAU + 0.5) * TAU;
    let mut cos_sign = 1.0;
    if r > FRAC_PI_2 {
        r = PI - r;
        cos_sign = -1.0;
    } else if r < -FRAC_PI_2 {
        r = -PI - r;
        cos_sign = -1.0;
    }
    let r2 = r * r;
    // Taylor series to x^15 / x^16: remainder below (pi/2)^17 / 17! ~ 6e-12.
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0
                    + r2 * (-1.0 / 5040.0
                        + r2 * (1.0 / 362_880.0
                            + r2 * (-1.0 / 39_916_800.0
                                + r2 * (1.0 / 6_227_020_800.0 - r2 / 1_307_674_368_000.0)))))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0
                    + r2 * (1.0 / 40_320.0
                        + r2 * (-1.0 / 3_628_800.0
                            + r2 * (1.0 / 479_001_600.0
                                + r2 * (-1.0 / 87_178_291_200.0 + r2 / 20_922_789_888_000.0)))))));
    (s, cos_sign * c)
}

/// Arctangent of y/x in (-pi, pi], like `atan2`.
pub fn atan2(y: f64, x: f64) -> f64 {
    if x == 0.0 && y == 0.0 {
        return 0.0;
    }
    let (ax, ay) = (x.abs(), y.abs());
    // Angle of (ax, ay) in [0, pi/2] from atan of a ratio in [0, 1].
    let a = if ay <= ax {
        atan_unit(ay / ax)
    } else {
        FRAC_PI_2 - atan_unit(ax / ay)
    };
    let a = if x < 0.0 { PI - a } else { a };
    if y < 0.0 {
        -a
    } else {
        a
    }
}

/// atan(t) for t in [0, 1]: shifted by pi/4 above tan(pi/8) so the series argument
/// stays below 0.42 (remainder under 1e-9 with terms to t^23).
fn atan_unit(t: f64) -> f64 {
    const TAN_PI_8: f64 = 0.414_213_562_373_095_1;
    let (base, u) = if t > TAN_PI_8 {
        (FRAC_PI_4, (t - 1.0) / (t + 1.0))
    } else {
        (0.0, t)
    };
    let u2 = u * u;
    let mut sum = 0.0;
    let mut k = 23.0;
    while k >= 1.0 {
        let term = 1.0 / k;
        sum = if (k as i32) % 4 == 1 {
            term + u2 * sum
        } else {
            -term + u2 * sum
        };
        k -= 2.0;
    }
    base + u * sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_std_over_several_turns() {
        for i in -2000..=2000 {
            let x = f64::from(i) * 0.0137;
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() < 1e-9, "{x}");
            assert!((c - x.cos()).abs() < 1e-9, "{x}");
        }
        for i in -50..=50 {
            for j in -50..=50 {
                let (y, x) = (f64::from(i) * 0.37, f64::from(j) * 0.29);
                if x == 0.0 && y == 0.0 {
                    continue;
                }
                assert!((atan2(y, x) - y.atan2(x)).abs() < 1e-9, "{y} {x}");
            }
        }
    }
}
