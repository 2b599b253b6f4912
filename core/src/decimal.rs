//! Decimal text without `core::fmt`: the byte [`Sink`] that replies are written to, and
//! the number writers and float-to-integer conversions the protocol, the settings
//! listing and the G-code interpreter share.

use crate::fmath;

/// A byte sink for the protocol's responses: replies are built from byte strings and
/// the number writers below, never through `core::fmt` (its machinery costs several KB
/// of flash on the Cortex-M3).
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

/// `a` in decimal with `decimals` digits after a point (at least one before it),
/// behind a `-` if `neg`. Long division by 10 over 16-bit limbs with the core's 32-bit
/// divide: no 64-bit division routine.
pub fn put_decimal(w: &mut dyn Sink, a: u64, neg: bool, decimals: usize) {
    let mut buf = [0u8; 24];
    let mut start = buf.len();
    let mut limbs = [
        (a >> 48) as u32,
        (a >> 32) as u32 & 0xFFFF,
        (a >> 16) as u32 & 0xFFFF,
        a as u32 & 0xFFFF,
    ];
    let mut k = 0;
    loop {
        let mut r = 0u32;
        let mut more = false;
        for l in limbs.iter_mut() {
            let cur = (r << 16) | *l;
            *l = cur / 10;
            r = cur % 10;
            more |= *l != 0;
        }
        start -= 1;
        if let Some(d) = buf.get_mut(start) {
            *d = b'0' + r as u8;
        }
        k += 1;
        if k == decimals {
            start -= 1;
            if let Some(d) = buf.get_mut(start) {
                *d = b'.';
            }
        }
        if !more && k > decimals {
            break;
        }
    }
    if neg {
        start -= 1;
        if let Some(d) = buf.get_mut(start) {
            *d = b'-';
        }
    }
    w.put(buf.get(start..).unwrap_or(&[]));
}

/// `x` rounded half away from zero to an `i32` (saturating): one copy of the
/// conversion's range checks for every caller.
#[inline(never)]
pub fn round_i32(x: f32) -> i32 {
    fmath::round(x) as i32
}

/// `x` truncated to a `u32` (saturating, NaN = 0), out of line for the same reason.
#[inline(never)]
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
