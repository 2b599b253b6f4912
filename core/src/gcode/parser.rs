//! Lexical layer: the [`LineCleaner`] that drops what Grbl drops (spaces, control
//! characters, `(...)` and `;` comments, block-delete `/`) and upper-cases the rest,
//! and [`WordBlock::parse`] that splits a cleaned line into words with Grbl's number rules.
//!
//! The cleaner works one byte at a time so that the protocol can clean while it reads
//! from its receive buffer and count the line length the way Grbl does (after
//! cleaning). The parser only checks syntax and repeats; meaning is the interpreter's.

use super::ErrorCode;
use crate::decimal::{div_rem, round_div};
use heapless::Vec;

/// Streaming comment/space stripper. Feed bytes of one line; [`LineCleaner::reset`]
/// at each line end.
#[derive(Clone, Copy, Debug, Default)]
pub struct LineCleaner {
    in_paren: bool,
    in_semicolon: bool,
}

impl LineCleaner {
    pub const fn new() -> Self {
        LineCleaner {
            in_paren: false,
            in_semicolon: false,
        }
    }
    pub fn reset(&mut self) {
        *self = Self::new();
    }
    /// Inside a `(...)` comment (the bytes pushed now are its text).
    pub fn in_comment(&self) -> bool {
        self.in_paren
    }
    /// The byte to keep for byte `b`, if any.
    pub fn push(&mut self, b: u8) -> Option<u8> {
        if self.in_semicolon {
            return None;
        }
        if self.in_paren {
            if b == b')' {
                self.in_paren = false;
            }
            return None;
        }
        match b {
            b'(' => {
                self.in_paren = true;
                None
            }
            b';' => {
                self.in_semicolon = true;
                None
            }
            // Spaces and control characters are ignored; '/' (block delete) too. DEL
            // is kept, as Grbl keeps it: it is no letter, so the line gets `error:1`
            // rather than running as if the byte had not been sent.
            0..=b' ' | b'/' => None,
            b'a'..=b'z' => Some(b - 32),
            _ => Some(b),
        }
    }
}

/// Clean a whole raw line into `out`; `Err(Overflow)` if the cleaned line is too long.
pub fn clean_line<const N: usize>(raw: &[u8], out: &mut Vec<u8, N>) -> Result<(), ErrorCode> {
    let mut c = LineCleaner::new();
    out.clear();
    for &b in raw {
        if let Some(k) = c.push(b) {
            out.push(k).map_err(|_| ErrorCode::Overflow)?;
        }
    }
    Ok(())
}

/// Maximum G and M words in one block (more is always a modal-group error anyway).
pub const MAX_CODES: usize = 8;

/// A G or M code as value x 10 (so G28.1 is 281).
pub type Code = u16;

/// A G-code number, exact: the decimal as written, in millionths. Six decimals are
/// kept, a seventh rounds (half away from zero) and further digits are dropped, so
/// lengths stay exact decimals (a millionth of a mm is a nanometre, the interpreter's
/// unit) and so do G and M codes and integer words. Feeds, times and settings, which
/// never accumulate, go to `f32` with [`Value::to_f32`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Value(i64);

/// One in millionths.
pub const ONE: i64 = 1_000_000;

impl Value {
    pub const fn from_millionths(v: i64) -> Value {
        Value(v)
    }
    pub fn millionths(self) -> i64 {
        self.0
    }
    pub fn to_f32(self) -> f32 {
        self.0 as f32 / ONE as f32
    }
    pub fn is_negative(self) -> bool {
        self.0 < 0
    }
    /// The value if it is a whole number.
    pub fn whole(self) -> Option<i64> {
        let (q, r) = div_rem(u128::from(self.0.unsigned_abs()), ONE as u32);
        let q = q as i64; // below 2^63 / 10^6
        (r == 0).then_some(if self.0 < 0 { -q } else { q })
    }
    /// Rounded to a whole number (half away from zero).
    pub fn round(self) -> i64 {
        round_div(i128::from(self.0), ONE as u32) as i64
    }
}

/// Letters that carry values (everything else except G and M is unsupported), each
/// with its slot in [`WordBlock`].
const VALUE_LETTERS: &[u8; 13] = b"FIJKLNPRSTXYZ";

/// The slot of a value letter.
fn slot(letter: u8) -> Option<usize> {
    VALUE_LETTERS.iter().position(|&l| l == letter)
}

/// One parsed block: the G and M codes in order, and the value words by letter.
/// A value word is present while its slot's bit is set in `present`: a mask and plain
/// numbers are smaller to test and clear than 13 `Option`s.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WordBlock {
    pub g: Vec<Code, MAX_CODES>,
    pub m: Vec<Code, MAX_CODES>,
    present: u16,
    values: [Value; 13],
}

impl WordBlock {
    /// Value word for `letter` (upper case), if present.
    pub fn get(&self, letter: u8) -> Option<Value> {
        let i = slot(letter)?;
        let v = *self.values.get(i)?;
        (self.present >> i & 1 != 0).then_some(v)
    }

    /// Remove and return the value word for `letter` (used to track unused words).
    pub fn take(&mut self, letter: u8) -> Option<Value> {
        let v = self.get(letter)?;
        if let Some(i) = slot(letter) {
            self.present &= !(1 << i);
        }
        Some(v)
    }

    /// Letters that still hold a value.
    pub fn any_value(&self) -> bool {
        self.present != 0
    }

    /// Parse a cleaned line (upper case, no spaces or comments).
    pub fn parse(line: &[u8]) -> Result<WordBlock, ErrorCode> {
        let mut b = WordBlock::default();
        b.parse_into(line)?;
        Ok(b)
    }

    /// [`WordBlock::parse`] into an empty block (no block moved through a `Result`).
    pub fn parse_into(&mut self, line: &[u8]) -> Result<(), ErrorCode> {
        let b = self;
        let mut rest = line;
        while let Some((&letter, tail)) = rest.split_first() {
            if !letter.is_ascii_uppercase() {
                return Err(ErrorCode::ExpectedCommandLetter);
            }
            let (value, used) = read_number(tail)?;
            rest = tail.get(used..).unwrap_or(&[]);
            match letter {
                b'G' | b'M' => {
                    // Grbl reads a negative code as no code it knows.
                    if value.is_negative() {
                        return Err(ErrorCode::UnsupportedCommand);
                    }
                    let code = code_of(value)?;
                    let list = if letter == b'G' { &mut b.g } else { &mut b.m };
                    list.push(code)
                        .map_err(|_| ErrorCode::ModalGroupViolation)?;
                }
                _ => {
                    let i = slot(letter).ok_or(ErrorCode::UnsupportedCommand)?;
                    if b.present & (1 << i) != 0 {
                        return Err(ErrorCode::WordRepeated);
                    }
                    b.present |= 1 << i;
                    if let Some(v) = b.values.get_mut(i) {
                        *v = value;
                    }
                }
            }
        }
        Ok(())
    }
}

/// G/M value to code x 10; only whole numbers and one decimal (G28.1) are codes.
fn code_of(value: Value) -> Result<Code, ErrorCode> {
    let v = value.millionths();
    if v > 999 * ONE {
        return Err(ErrorCode::UnsupportedCommand);
    }
    // Tenths: 0 ..= 9990 (the value is not negative here).
    match div_rem(u128::from(v.unsigned_abs()), (ONE / 10) as u32) {
        (tenths, 0) => Ok(tenths as Code),
        _ => Err(ErrorCode::CommandValueNotInteger),
    }
}

/// Read a number as Grbl does: optional sign, digits with at most one decimal point,
/// no exponent; exactly, in millionths (see [`Value`]). Returns the value and the
/// bytes used. Integer parts of 9,223,372,036,854 and more are `error:2`.
pub fn read_number(s: &[u8]) -> Result<(Value, usize), ErrorCode> {
    let mut i = 0;
    let mut negative = false;
    if let Some(&c) = s.first() {
        if c == b'-' || c == b'+' {
            negative = c == b'-';
            i = 1;
        }
    }
    let mut whole: i64 = 0;
    // The first seven decimals in units of 10^-7 (each digit at its place's weight;
    // further digits weigh 0), so that the seventh rounds the sixth.
    let mut frac = 0u32;
    let mut place = 10_000_000u32;
    let mut any_digit = false;
    let mut seen_point = false;
    while let Some(&c) = s.get(i) {
        match c {
            b'0'..=b'9' => {
                any_digit = true;
                let digit = c - b'0';
                if !seen_point {
                    // No overflow: `whole` stays below i64::MAX / ONE (< 2^44).
                    whole = whole * 10 + i64::from(digit);
                    if whole >= i64::MAX / ONE {
                        return Err(ErrorCode::BadNumberFormat);
                    }
                } else {
                    place /= 10;
                    frac += u32::from(digit) * place;
                }
            }
            b'.' if !seen_point => seen_point = true,
            _ => break,
        }
        i += 1;
    }
    if !any_digit {
        return Err(ErrorCode::BadNumberFormat);
    }
    let v = whole * ONE + i64::from((frac + 5) / 10);
    Ok((Value(if negative { -v } else { v }), i))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cleaned(s: &str) -> Vec<u8, 128> {
        let mut v = Vec::new();
        clean_line(s.as_bytes(), &mut v).unwrap();
        v
    }

    #[test]
    fn cleaner_drops_spaces_comments_and_folds_case() {
        assert_eq!(&cleaned("g1 x 1 0 (move) y-2.5 ; tail")[..], b"G1X10Y-2.5");
        assert_eq!(&cleaned("(only a comment)")[..], b"");
        assert_eq!(&cleaned("/G0\tX1\r")[..], b"G0X1");
    }

    fn v(millionths: i64) -> Value {
        Value::from_millionths(millionths)
    }

    #[test]
    fn numbers_follow_grbl_rules_exactly() {
        assert_eq!(read_number(b"12.5X"), Ok((v(12_500_000), 4)));
        assert_eq!(read_number(b"-.5"), Ok((v(-500_000), 3)));
        assert_eq!(read_number(b"+3"), Ok((v(3_000_000), 2)));
        assert_eq!(read_number(b"1.2.3"), Ok((v(1_200_000), 3)));
        // Six decimals kept, the seventh rounds half away from zero, the rest dropped.
        assert_eq!(read_number(b"0.000123456789"), Ok((v(123), 14)));
        assert_eq!(read_number(b"-0.0000125"), Ok((v(-13), 10)));
        assert_eq!(read_number(b"0.9999995"), Ok((v(1_000_000), 9)));
        assert_eq!(read_number(b"0.000000000000001"), Ok((v(0), 17)));
        // 0.1 and 0.0125 are exact (no binary fraction in between).
        assert_eq!(read_number(b"0.1"), Ok((v(100_000), 3)));
        assert_eq!(read_number(b"0.0125"), Ok((v(12_500), 6)));
        assert_eq!(
            read_number(b"9223372.036854"),
            Ok((v(9_223_372_036_854), 14))
        );
        assert_eq!(read_number(b"-"), Err(ErrorCode::BadNumberFormat));
        assert_eq!(read_number(b"."), Err(ErrorCode::BadNumberFormat));
        assert_eq!(read_number(b"X"), Err(ErrorCode::BadNumberFormat));
        assert_eq!(
            read_number(b"99999999999999999999999"),
            Err(ErrorCode::BadNumberFormat)
        );
        assert_eq!(
            read_number(b"9223372036855"),
            Err(ErrorCode::BadNumberFormat)
        );
        assert_eq!(v(2_500_000).to_f32(), 2.5);
        assert_eq!(v(3_000_000).whole(), Some(3));
        assert_eq!(v(3_000_001).whole(), None);
        assert_eq!((v(-2_500_000).round(), v(2_499_999).round()), (-3, 2));
    }

    proptest::proptest! {
        /// Any sign, whole part and decimals: the whole part and six decimals exactly,
        /// the seventh decimal rounding, the rest dropped; up to the first byte that
        /// is not part of the number.
        #[test]
        fn numbers_are_exact_millionths(
            sign in 0usize..3,
            whole in proptest::option::of(0u64..9_223_372_036_854),
            decimals in proptest::option::of("[0-9]{0,12}"),
        ) {
            let mut text = ["", "-", "+"][sign].to_string();
            if let Some(w) = whole {
                text += &w.to_string();
            }
            if let Some(d) = &decimals {
                text += ".";
                text += d;
            }
            let used = text.len();
            text += "X1";
            let digits = decimals.as_deref().unwrap_or("");
            let want = if whole.is_none() && digits.is_empty() {
                Err(ErrorCode::BadNumberFormat)
            } else {
                let six: std::string::String = digits.chars().chain("000000".chars()).take(6).collect();
                let seventh = digits.as_bytes().get(6).is_some_and(|&d| d >= b'5');
                let v = whole.unwrap_or(0) as i64 * ONE + six.parse::<i64>().unwrap() + i64::from(seventh);
                Ok((Value(if sign == 1 { -v } else { v }), used))
            };
            proptest::prop_assert_eq!(read_number(text.as_bytes()), want);
        }
    }

    #[test]
    fn blocks_split_into_codes_and_words() {
        let b = WordBlock::parse(b"G1G91.1X10Y-2F300M3").unwrap();
        assert_eq!(&b.g[..], &[10, 911]);
        assert_eq!(&b.m[..], &[30]);
        assert_eq!(b.get(b'X'), Some(v(10_000_000)));
        assert_eq!(b.get(b'F'), Some(v(300_000_000)));
        assert_eq!(b.get(b'Z'), None);
        assert_eq!(WordBlock::parse(b"X1X2"), Err(ErrorCode::WordRepeated));
        assert_eq!(
            WordBlock::parse(b"1"),
            Err(ErrorCode::ExpectedCommandLetter)
        );
        assert_eq!(WordBlock::parse(b"XA"), Err(ErrorCode::BadNumberFormat));
        assert_eq!(WordBlock::parse(b"A1"), Err(ErrorCode::UnsupportedCommand));
        assert_eq!(
            WordBlock::parse(b"G1.55"),
            Err(ErrorCode::CommandValueNotInteger)
        );
        assert_eq!(WordBlock::parse(b"G-1"), Err(ErrorCode::UnsupportedCommand));
    }
}
