//! Fixed-point text formatting of f32 values ("-12.35") for the LCD and messages.
//!
//! core's `{:.2}` float formatting pulls several KB of flash into the firmware; the
//! screens only ever need a few decimals of a bounded value, so it is done here with
//! integer formatting. Values too large for the requested width print as "----".

use core::fmt::Write;
use heapless::String;

/// Append `v` with exactly `decimals` (0..=3) digits after the point. Non-finite or
/// huge values append "----". Returns false if `out` ran out of room.
pub fn push_fixed<const N: usize>(out: &mut String<N>, v: f32, decimals: u8) -> bool {
    let decimals = decimals.min(3);
    let scale = [1.0f32, 10.0, 100.0, 1000.0][decimals as usize];
    let scaled = libm::roundf(v * scale);
    if !scaled.is_finite() || scaled.abs() >= 1.0e9 {
        return out.push_str("----").is_ok();
    }
    let n = scaled as i64;
    let neg = n < 0;
    let n = n.unsigned_abs();
    let div = scale as u64;
    let int = n / div;
    let frac = n % div;
    let sign = if neg { "-" } else { "" };
    match decimals {
        0 => write!(out, "{sign}{int}"),
        1 => write!(out, "{sign}{int}.{frac:01}"),
        2 => write!(out, "{sign}{int}.{frac:02}"),
        _ => write!(out, "{sign}{int}.{frac:03}"),
    }
    .is_ok()
}

/// `v` as a new string (see [`push_fixed`]).
pub fn fixed<const N: usize>(v: f32, decimals: u8) -> String<N> {
    let mut s = String::new();
    push_fixed(&mut s, v, decimals);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_signs_rounding_and_small_negatives() {
        assert_eq!(fixed::<12>(12.345, 2).as_str(), "12.35");
        assert_eq!(fixed::<12>(-0.04, 1).as_str(), "0.0");
        assert_eq!(fixed::<12>(-0.06, 1).as_str(), "-0.1");
        assert_eq!(fixed::<12>(-3.0, 0).as_str(), "-3");
        assert_eq!(fixed::<12>(0.2, 3).as_str(), "0.200");
        assert_eq!(fixed::<12>(f32::NAN, 2).as_str(), "----");
        assert_eq!(fixed::<12>(1.0e12, 2).as_str(), "----");
    }

    #[test]
    fn reports_overflow_of_the_output() {
        let mut s: String<3> = String::new();
        assert!(!push_fixed(&mut s, 1234.5, 1));
    }
}
