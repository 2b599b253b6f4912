//! Fixed-point text formatting of f32 values ("-12.35") for the LCD and messages.
//!
//! The screens only ever need a few decimals of a bounded value, rounded the way the
//! protocol's replies round them, so it is done with integer formatting, through the
//! same decimal writer as those replies ([`crate::decimal`]), not `core::fmt`. Values too large for the requested width print as "----".

use super::text::Text;
use crate::decimal::{decimal, round_i32, DECIMAL_MAX};

/// Longest text produced: "-999999999.999".
pub type Fixed = Text<16>;

/// `v` rounded to an integer ([`round_i32`]) if finite and below 10^9 in magnitude.
pub fn round_checked(v: f32) -> Option<i32> {
    let n = round_i32(v);
    (v.is_finite() && n.unsigned_abs() < 1_000_000_000).then_some(n)
}

/// A number to show: n / 10^decimals with a sign (`true`: negative), or None for a
/// value that cannot be shown ("----").
pub type Number = Option<(bool, u32)>;

/// `v` scaled to `decimals` (at most 3) digits after the point and rounded; None if
/// not finite or too large.
pub fn scaled(v: f32, decimals: u8) -> Number {
    let scale: u32 = [1, 10, 100, 1000][usize::from(decimals.min(3))];
    round_checked(v * scale as f32).map(|n| (n < 0, n.unsigned_abs()))
}

/// Append `num` with `decimals` digits after the point ("-" first if negative and not
/// 0, at least one integer digit: "0.05", "----" for None), right-aligned in `width`
/// characters, to the text `buf[..*len]`: whole, or nothing and false if it does not
/// fit. The digits come from the protocol's writer, [`decimal`]; one routine for every
/// text capacity.
pub(super) fn append_number(
    buf: &mut [u8],
    len: &mut u8,
    num: Number,
    decimals: u8,
    width: usize,
) -> bool {
    // The number at the end of `text`, padded with spaces in front to `width`.
    let mut text = [b' '; DECIMAL_MAX];
    let n = match num {
        None => {
            if let Some(dashes) = text.get_mut(DECIMAL_MAX - 4..) {
                dashes.fill(b'-');
            }
            4
        }
        Some((neg, n)) => decimal(&mut text, u64::from(n), neg && n != 0, decimals.into()),
    };
    let shown = n.max(width.min(DECIMAL_MAX));
    super::text::append(buf, len, text.get(DECIMAL_MAX - shown..).unwrap_or(&[]))
}

/// `v` with exactly `decimals` (0..=3) digits after the point; "----" if not finite
/// or too large.
pub fn format(v: f32, decimals: u8) -> Fixed {
    fixed(v, decimals)
}

/// `n` in decimal.
pub fn uint(n: u32) -> Fixed {
    let mut s = Text::new();
    s.push_uint(n, 0);
    s
}

/// Append [`format`]`(v, decimals)`; false if `out` ran out of room.
pub fn push_fixed<const N: usize>(out: &mut Text<N>, v: f32, decimals: u8) -> bool {
    out.push_fixed(v, decimals)
}

/// `v` as a new text (see [`format`]).
pub fn fixed<const N: usize>(v: f32, decimals: u8) -> Text<N> {
    let mut s = Text::new();
    s.push_fixed(v, decimals);
    s
}

/// Append the unsigned integer `n` right-aligned in `width` characters.
pub fn push_uint<const N: usize>(out: &mut Text<N>, n: u32, width: usize) -> bool {
    out.push_uint(n, width)
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
        assert_eq!(fixed::<12>(0.0, 0).as_str(), "0");
        assert_eq!(fixed::<12>(0.05, 2).as_str(), "0.05");
        assert_eq!(fixed::<16>(-12345.678, 3).as_str(), "-12345.678");
    }

    #[test]
    fn round_checked_is_round_then_cast_below_a_billion() {
        let mut cases = std::vec![
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            0.49999997,
            1.5,
            2.5,
            -2.5,
            8388607.5,
            8388608.0,
            16777215.0,
            2147483520.0,
            2147483648.0,
            -2147483648.0,
            -2147483904.0,
            1.0e20,
            -1.0e20,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1.0e-40,
            -1.0e-40,
        ];
        // And a spread of bit patterns over every exponent.
        let mut x = 0x1234_5678u32;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            cases.push(f32::from_bits(x));
        }
        for v in cases {
            let want = libm::roundf(v) as i32;
            assert_eq!(round_i32(v), want, "{v:e} ({:#x})", v.to_bits());
            let checked = (v.is_finite() && want.unsigned_abs() < 1_000_000_000).then_some(want);
            assert_eq!(round_checked(v), checked, "{v:e}");
        }
    }

    #[test]
    fn right_aligned_integers() {
        let mut s: Text<12> = Text::new();
        assert!(push_uint(&mut s, 600, 5));
        assert!(push_uint(&mut s, 12345, 2));
        assert_eq!(s.as_str(), "  60012345");
        let mut big: Text<12> = Text::new();
        assert!(push_uint(&mut big, u32::MAX, 0));
        assert_eq!(big.as_str(), "4294967295");
    }

    #[test]
    fn reports_overflow_of_the_output() {
        let mut s: Text<3> = Text::new();
        assert!(!push_fixed(&mut s, 1234.5, 1));
    }
}
