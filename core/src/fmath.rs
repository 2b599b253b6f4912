//! f32 math for the firmware's task code, without libm and without f64.
//!
//! The Cortex-M3 has no FPU, so every f32 operation is a soft-float call, and libm's
//! f32 functions lean on f64 kernels and Payne-Hanek reduction tables that drag the
//! whole double-precision library (several KB) into the image. These are the few
//! functions the core needs, written to be small:
//! - `sqrt`, `trunc`, `floor`, `ceil`, `round`, `abs` are exact (bit-identical to libm);
//! - `hypot` is `sqrt(x² + y²)` in f32, within 1 ulp for the machine's ranges
//!   (|x|, |y| < 1e18, far beyond any travel in steps or millimetres);
//! - `sin`, `cos`, `sin_cos`, `atan2` use a three-part pi/2 reduction and short minimax
//!   polynomials (classic Cephes-style coefficients), absolute error below 3e-7 for
//!   |x| < 1e4 rad: far below one step of any drawing.
//!
//! And one integer function, `isqrt` (exact, digit by digit: no division, no float).
//!
//! No interrupt code uses floats at all; this is for planning and HMI tasks.

use core::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// |x|.
#[inline]
pub fn abs(x: f32) -> f32 {
    f32::from_bits(x.to_bits() & 0x7fff_ffff)
}

/// floor(sqrt(v)), exact: one bit of the root per step, by subtraction only (about
/// 32 steps; for the rare roots far from any guess, and once per arc).
pub fn isqrt(v: u64) -> u64 {
    if v == 0 {
        return 0;
    }
    let mut r = 0u64;
    let mut bit = 1u64 << ((63 - v.leading_zeros()) & !1);
    let mut rem = v;
    while bit != 0 {
        if rem >= r + bit {
            rem -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    r
}

/// x rounded toward zero.
pub fn trunc(x: f32) -> f32 {
    let bits = x.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32 - 127;
    if exp >= 23 {
        return x; // already an integer, or inf/NaN
    }
    if exp < 0 {
        return f32::from_bits(bits & 0x8000_0000); // |x| < 1: signed zero
    }
    f32::from_bits(bits & !(0x007f_ffff >> exp))
}

/// Largest integer not above x.
pub fn floor(x: f32) -> f32 {
    let t = trunc(x);
    if x < t {
        t - 1.0
    } else {
        t
    }
}

/// Smallest integer not below x.
pub fn ceil(x: f32) -> f32 {
    let t = trunc(x);
    if x > t {
        t + 1.0
    } else {
        t
    }
}

/// x rounded to the nearest integer, halves away from zero (like C's `roundf`).
pub fn round(x: f32) -> f32 {
    let t = trunc(x);
    // x - t is exact: both share the same binade or t is zero.
    if abs(x - t) >= 0.5 {
        t + if x < 0.0 { -1.0 } else { 1.0 }
    } else {
        t
    }
}

/// Correctly rounded square root (NaN for negative input), in integers only: the
/// 24-bit root of the significand by Newton steps on the M3's 32-bit hardware divide,
/// then an exact remainder check (one `umull`) for the rounding (checked against the
/// hardware's square root on every f32: the ignored test
/// `sqrt_on_every_f32_is_the_hardware_root`). About 60 instructions on the M3, where
/// bit-by-bit digits took 400: the planner takes several roots per G-code line.
pub fn sqrt(x: f32) -> f32 {
    let bits = x.to_bits();
    if bits & 0x7FFF_FFFF == 0 || bits == 0x7F80_0000 {
        return x; // +-0 and +infinity
    }
    if bits > 0x7F80_0000 {
        return f32::NAN; // negative (sign bit set) or NaN
    }
    let mut e = (bits >> 23) as i32 - 127;
    let mut m = bits & 0x007f_ffff;
    if e == -127 {
        // Subnormal: normalise the significand.
        let shift = m.leading_zeros() as i32 - 8;
        m <<= shift;
        e = -126 - shift;
    }
    // x = (m / 2^23) * 2^e; with e odd, fold one factor 2 into m so e/2 is whole.
    m |= 0x0080_0000;
    if e & 1 != 0 {
        m <<= 1;
    }
    // n = m * 2^23 lies in [2^46, 2^48): its root, in [2^23, 2^24), is the result's
    // significand. First the 16-bit root of n's top 32 bits `a`, by Newton steps from
    // the tangent of the root at 2^32 (above it everywhere, by 25 % at most: three
    // steps reach it), then one Newton step at full width, then the exact floor.
    let n = u64::from(m) << 23;
    let a = (n >> 16) as u32;
    let mut s = (a >> 17) + 0x8000;
    for _ in 0..3 {
        s = (s + a / s) >> 1;
    }
    let q0 = s << 8;
    // An integer Newton step never lands below the floor of the root, and from q0
    // (within about 2^9 of the root) at most one above it.
    let mut r = (q0 + div_48_by_24(n, q0)) >> 1;
    if u64::from(r) * u64::from(r) > n {
        r -= 1;
    }
    // Round to nearest: up when n - r^2 > r (the root is then above r + 1/2; a square
    // root is never exactly halfway).
    r += u32::from(n - u64::from(r) * u64::from(r) > u64::from(r));
    f32::from_bits((r + 0x3f00_0000).wrapping_add(((e >> 1) << 23) as u32))
}

/// `n / d` for `n` below 2^48 and `d` in [2^23, 2^24], with 32-bit divides only (a
/// u64 division is a long software routine on the M3): the top 32 bits, then two more
/// bytes, each with the remainder (below 2^24) in front.
fn div_48_by_24(n: u64, d: u32) -> u32 {
    let top = (n >> 16) as u32;
    let (q1, r1) = (top / d, top % d);
    let mid = (r1 << 8) | ((n >> 8) as u32 & 0xFF);
    let (q2, r2) = (mid / d, mid % d);
    let low = (r2 << 8) | (n as u32 & 0xFF);
    (q1 << 16) | (q2 << 8) | (low / d)
}

/// sqrt(x² + y²).
pub fn hypot(x: f32, y: f32) -> f32 {
    sqrt(x * x + y * y)
}

/// Sine and cosine of `x` radians.
pub fn sin_cos(x: f32) -> (f32, f32) {
    // Quadrant n and remainder r = x - n pi/2 in [-pi/4, pi/4], with pi/2 split into
    // three parts (the first short, so n * P1 is exact); tested to |x| = 1e4.
    const P1: f32 = 1.570_312_5;
    const P2: f32 = 4.837_513e-4;
    const P3: f32 = 7.549_79e-8;
    let n = round(x * (2.0 / PI));
    let r = ((x - n * P1) - n * P2) - n * P3;
    let z = r * r;
    let s = r + r * z * ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 0.166_666_55);
    let c = 1.0 - 0.5 * z + z * z * ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2);
    // Quadrant q: (s, c), (c, -s), (-s, -c), (-c, s): odd q swaps, q = 2, 3 negate the
    // sine, q = 1, 2 the cosine.
    let q = n as i32;
    let (s, c) = if q & 1 != 0 { (c, s) } else { (s, c) };
    let s = if q & 2 != 0 { -s } else { s };
    let c = if (q + 1) & 2 != 0 { -c } else { c };
    (s, c)
}

/// sin x.
pub fn sin(x: f32) -> f32 {
    sin_cos(x).0
}

/// cos x.
pub fn cos(x: f32) -> f32 {
    sin_cos(x).1
}

/// Arctangent of y/x in [-pi, pi], like C's `atan2f` (0 for the origin).
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (abs(x), abs(y));
    if ax == 0.0 && ay == 0.0 {
        return if x.is_sign_negative() {
            PI.copysign(y)
        } else {
            0.0f32.copysign(y)
        };
    }
    // Angle of (ax, ay) in [0, pi/2] from an arctangent of a ratio in [0, 1].
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

/// atan t for t in [0, 1].
fn atan_unit(t: f32) -> f32 {
    // Above tan(pi/8), use atan t = pi/4 + atan((t - 1) / (t + 1)).
    let (base, t) = if t > 0.414_213_57 {
        (FRAC_PI_4, (t - 1.0) / (t + 1.0))
    } else {
        (0.0, t)
    };
    let z = t * t;
    base + t
        + t * z * (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// Every one of the 2^32 inputs against the host's hardware square root (bit for
    /// bit, NaN for NaN): 36 s on two cores, so run on demand with `cargo test -p
    /// inkstep-core --target host-tuple --profile host --lib sqrt_on_every_f32 --
    /// --ignored`.
    #[test]
    #[ignore]
    fn sqrt_on_every_f32_is_the_hardware_root() {
        let threads = 4u64;
        let span = (1u64 << 32) / threads;
        let workers: std::vec::Vec<_> = (0..threads)
            .map(|t| {
                std::thread::spawn(move || {
                    for bits in t * span..(t + 1) * span {
                        let x = f32::from_bits(bits as u32);
                        assert!(same(sqrt(x), x.sqrt()), "sqrt of {x:e} ({bits:#x})");
                    }
                })
            })
            .collect();
        for w in workers {
            w.join().unwrap();
        }
    }

    #[test]
    fn exact_functions_match_libm_on_edge_values() {
        let edges = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.499_999_97,
            1e-45,
            1.17e-38,
            8_388_607.5,
            8_388_608.0,
            16_777_217.0,
            3.4e38,
            f32::INFINITY,
            -f32::INFINITY,
            f32::NAN,
            -3.0,
        ];
        for x in edges {
            assert!(same(sqrt(x), libm::sqrtf(x)), "sqrt {x}");
            assert!(same(trunc(x), libm::truncf(x)), "trunc {x}");
            assert!(same(floor(x), libm::floorf(x)), "floor {x}");
            assert!(same(ceil(x), libm::ceilf(x)), "ceil {x}");
            assert!(same(round(x), libm::roundf(x)), "round {x}");
            assert!(same(abs(x), libm::fabsf(x)), "abs {x}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        #[test]
        fn exact_functions_match_libm(bits in any::<u32>()) {
            let x = f32::from_bits(bits);
            prop_assert!(same(sqrt(x), libm::sqrtf(x)), "sqrt {x:e}");
            prop_assert!(same(trunc(x), libm::truncf(x)), "trunc {x:e}");
            prop_assert!(same(floor(x), libm::floorf(x)), "floor {x:e}");
            prop_assert!(same(ceil(x), libm::ceilf(x)), "ceil {x:e}");
            prop_assert!(same(round(x), libm::roundf(x)), "round {x:e}");
        }

        #[test]
        fn sin_cos_within_3e7(x in -1.0e4f32..1.0e4) {
            let (s, c) = sin_cos(x);
            let xd = f64::from(x);
            prop_assert!((f64::from(s) - xd.sin()).abs() < 3e-7, "sin {x}: {s}");
            prop_assert!((f64::from(c) - xd.cos()).abs() < 3e-7, "cos {x}: {c}");
        }

        #[test]
        fn atan2_within_3e7(y in -1.0e6f32..1.0e6, x in -1.0e6f32..1.0e6) {
            let a = atan2(y, x);
            prop_assert!((f64::from(a) - f64::from(y).atan2(f64::from(x))).abs() < 3e-7, "atan2 {y} {x}: {a}");
        }

        #[test]
        fn hypot_within_one_ulp(x in -1.0e9f32..1.0e9, y in -1.0e9f32..1.0e9) {
            let h = hypot(x, y);
            let exact = f64::from(x).hypot(f64::from(y));
            prop_assert!((f64::from(h) - exact).abs() <= exact * 1.2e-7, "hypot {x} {y}: {h}");
        }
    }

    #[test]
    fn atan2_signs_and_axes() {
        assert_eq!(atan2(0.0, 1.0), 0.0);
        assert_eq!(atan2(1.0, 0.0), FRAC_PI_2);
        assert_eq!(atan2(0.0, -1.0), PI);
        assert_eq!(atan2(-1.0, 0.0), -FRAC_PI_2);
        assert_eq!(atan2(0.0, 0.0), 0.0);
    }
}
