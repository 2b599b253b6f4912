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
//! No interrupt code uses floats at all; this is for planning and HMI tasks.

use core::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// |x|.
#[inline]
pub fn abs(x: f32) -> f32 {
    f32::from_bits(x.to_bits() & 0x7fff_ffff)
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

/// Correctly rounded square root (NaN for negative input): the root's 25 bits (24 and
/// a rounding bit) digit by digit in 32-bit integers, no table, no division, no u64
/// (checked against the hardware's square root on every f32: the ignored test
/// `sqrt_on_every_f32_is_the_hardware_root`).
/// `!(x >= 0.0)` on purpose: one comparison is false for NaN and negatives alike.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn sqrt(x: f32) -> f32 {
    if !(x >= 0.0) {
        return f32::NAN;
    }
    if x == 0.0 || x == f32::INFINITY {
        return x;
    }
    let bits = x.to_bits();
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
    // Root bit by bit from 2^24 (the leading 1) down: `rem` is the remainder, doubled
    // at every step so it stays aligned with the next bit; `s` is twice the root so far.
    let mut rem = m << 1;
    let (mut q, mut s, mut bit) = (0u32, 0u32, 0x0100_0000u32);
    while bit != 0 {
        let t = s + bit;
        if t <= rem {
            s = t + bit;
            rem -= t;
            q += bit;
        }
        rem <<= 1;
        bit >>= 1;
    }
    // Round to nearest on the extra bit (a square root is never exactly halfway).
    q += q & 1;
    f32::from_bits(((q >> 1) + 0x3f00_0000).wrapping_add(((e >> 1) << 23) as u32))
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
