//! Decimal text without `core::fmt`: the byte [`Sink`] that replies are written to, and
//! the number writers and float-to-integer conversions the protocol, the settings
//! listing and the G-code interpreter share; and the one long division ([`div_rem`])
//! that wide integers (the interpreter's exact lengths, the digits of a number) go
//! through, in 32-bit steps the Cortex-M3 divides in hardware.

use crate::fmath;

/// A byte sink for the protocol's responses: replies are built from byte strings and
/// the number writers below, never through `core::fmt`: integer digits, the exact
/// decimal rounding Grbl's replies use, and no formatting machinery in the protocol
/// task's time.
pub trait Sink {
    fn put(&mut self, bytes: &[u8]);
}

impl<const N: usize> Sink for heapless::Vec<u8, N> {
    fn put(&mut self, bytes: &[u8]) {
        let _ = self.extend_from_slice(bytes);
    }
}

impl<const N: usize> Sink for heapless::String<N> {
    fn put(&mut self, bytes: &[u8]) {
        for &b in bytes {
            let _ = self.push(char::from(b));
        }
    }
}

/// `n / d` and `n % d` for a divisor `1 <= d < 2^24`, by long division over bytes with
/// the core's 32-bit divide (the remainder stays below 2^24, so a remainder and the
/// next byte fit 32 bits). `d = 0` gives (0, 0).
pub fn div_rem(n: u128, d: u32) -> (u128, u32) {
    if d == 0 {
        return (0, 0);
    }
    let mut q = n.to_be_bytes();
    let mut r = 0u32;
    // Leading zero bytes divide to zero bytes with no remainder.
    for byte in q.iter_mut().skip((n.leading_zeros() / 8) as usize) {
        let cur = (r << 8) | u32::from(*byte);
        *byte = (cur / d) as u8; // below 256: r < d
        r = cur % d;
    }
    (u128::from_be_bytes(q), r)
}

/// `a / d` rounded half away from zero, for a divisor `1 <= d < 2^24`.
pub fn round_div(a: i128, d: u32) -> i128 {
    let (q, r) = div_rem(a.unsigned_abs(), d);
    let q = q + u128::from(u64::from(r) * 2 >= u64::from(d));
    let q = i128::try_from(q).unwrap_or(i128::MAX);
    if a < 0 {
        -q
    } else {
        q
    }
}

/// `a` in decimal with `decimals` digits after a point (at least one before it),
/// behind a `-` if `neg`.
pub fn put_decimal(w: &mut dyn Sink, a: u64, neg: bool, decimals: usize) {
    let mut buf = [0u8; DECIMAL_MAX];
    let n = decimal(&mut buf, a, neg, decimals);
    w.put(buf.get(buf.len() - n..).unwrap_or(&[]));
}

/// The longest text [`decimal`] writes: 20 digits of a u64, a point and a sign.
pub const DECIMAL_MAX: usize = 24;

/// The one decimal writer: `a` in decimal with `decimals` digits after a point (at
/// least one before it), behind a `-` if `neg`, at the end of `buf`; returns its
/// length. Long division by 10 over 16-bit limbs with the core's 32-bit divide: no
/// 64-bit division routine.
pub fn decimal(buf: &mut [u8; DECIMAL_MAX], a: u64, neg: bool, decimals: usize) -> usize {
    let mut start = buf.len();
    let mut rest = u128::from(a);
    let mut k = 0;
    loop {
        let (q, digit) = div_rem(rest, 10);
        rest = q;
        start -= 1;
        if let Some(d) = buf.get_mut(start) {
            *d = b'0' + digit as u8;
        }
        k += 1;
        if k == decimals {
            start -= 1;
            if let Some(d) = buf.get_mut(start) {
                *d = b'.';
            }
        }
        if rest == 0 && k > decimals {
            break;
        }
    }
    if neg {
        start -= 1;
        if let Some(d) = buf.get_mut(start) {
            *d = b'-';
        }
    }
    buf.len() - start
}

/// `x` rounded half away from zero to an `i32` (saturating).
pub fn round_i32(x: f32) -> i32 {
    fmath::round(x) as i32
}

/// `x` truncated to a `u32` (saturating, NaN = 0).
pub fn to_u32(x: f32) -> u32 {
    x as u32
}

/// A whole number in decimal.
pub fn put_int(w: &mut dyn Sink, v: i32) {
    put_decimal(w, u64::from(v.unsigned_abs()), v < 0, 0);
}

/// Write `v` with three decimals (Grbl's report format) through integer formatting.
/// Values round half away from zero, in f32 (no double-precision routines in the
/// image): exact to the last digit below 16,777 (2^24 thousandths), which covers any
/// plotter; larger values keep f32's 7 significant digits, and values beyond i64
/// thousandths saturate. NaN prints as 0.000.
pub fn write_fixed3(w: &mut dyn Sink, v: f32) {
    let milli = fmath::round(v * 1000.0) as i64;
    put_decimal(w, milli.unsigned_abs(), milli < 0, 3);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_division_matches_the_builtin_one() {
        let mut x = 0x9E37_79B9_7F4A_7C15_F39C_C060_5CED_C834u128;
        for d in [1u32, 2, 3, 5, 10, 1000, 15_625, 1_000_000, (1 << 24) - 1] {
            for _ in 0..200 {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                for n in [x, x >> 40, x >> 90, x & 0xFFFF, 0] {
                    assert_eq!(
                        div_rem(n, d),
                        (n / u128::from(d), (n % u128::from(d)) as u32)
                    );
                }
            }
        }
        assert_eq!(round_div(15, 10), 2);
        assert_eq!(round_div(-15, 10), -2);
        assert_eq!(round_div(14, 10), 1);
        assert_eq!(round_div(-14, 10), -1);
        assert_eq!(round_div(7, 2), 4);
    }

    #[test]
    fn fixed_point_output_matches_three_decimal_rounding() {
        for v in [
            0.0f32, 1.0, -1.0, 0.0005, -0.0004, 123.456, -99.9996, 0.010, 16_000.125, -2.5e-4,
        ] {
            let mut a: heapless::String<40> = heapless::String::new();
            write_fixed3(&mut a, v);
            let want = std::format!("{:.3}", f64::from(v));
            let want = if want == "-0.000" {
                "0.000".into()
            } else {
                want
            };
            assert_eq!(a.as_str(), want, "{v}");
        }
    }

    #[test]
    fn fixed_point_output_is_the_i64_rounding_everywhere() {
        // The reference: f32 rounding to thousandths, then i64 digits.
        fn reference(v: f32) -> std::string::String {
            let milli = libm::roundf(v * 1000.0) as i64;
            let sign = if milli < 0 { "-" } else { "" };
            let a = milli.unsigned_abs();
            std::format!("{}{}.{:03}", sign, a / 1000, a % 1000)
        }
        let mut vals = std::vec![
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            -f32::MAX,
            4_294_967.0,
            4_294_967.5,
            -4_294_968.0,
            1.0e9,
            -3.5e12,
            -0.0,
            -0.0005,
            -0.00049,
        ];
        let mut x = 0x2545_f491u32;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let v = f32::from_bits(x);
            if v.is_finite() {
                vals.push(v);
                vals.push(v / 1.0e30);
            }
        }
        for v in vals {
            let mut a: heapless::String<40> = heapless::String::new();
            write_fixed3(&mut a, v);
            assert_eq!(a.as_str(), reference(v), "{v:e}");
        }
    }
}
