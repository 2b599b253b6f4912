//! Lexical layer: the [`LineCleaner`] that drops what Grbl drops (spaces, control
//! characters, `(...)` and `;` comments, block-delete `/`) and upper-cases the rest,
//! and [`Block::parse`] that splits a cleaned line into words with Grbl's number rules.
//!
//! The cleaner works one byte at a time so that the protocol can clean while it reads
//! from its receive buffer and count the line length the way Grbl does (after
//! cleaning). The parser only checks syntax and repeats; meaning is the interpreter's.

use super::Status;
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
            // Spaces and control characters are ignored; '/' (block delete) too.
            0..=b' ' | b'/' | 0x7F.. => None,
            b'a'..=b'z' => Some(b - 32),
            _ => Some(b),
        }
    }
}

/// Clean a whole raw line into `out`; `Err(Overflow)` if the cleaned line is too long.
pub fn clean_line<const N: usize>(raw: &[u8], out: &mut Vec<u8, N>) -> Result<(), Status> {
    let mut c = LineCleaner::new();
    out.clear();
    for &b in raw {
        if let Some(k) = c.push(b) {
            out.push(k).map_err(|_| Status::Overflow)?;
        }
    }
    Ok(())
}

/// Maximum G and M words in one block (more is always a modal-group error anyway).
pub const MAX_CODES: usize = 8;

/// A G or M code as value x 10 (so G28.1 is 281).
pub type Code = u16;

/// One parsed block: the G and M codes in order, and the value words by letter.
/// A value word is present while its bit (A = bit 0) is set in `present`: a mask and
/// plain floats are smaller to test and clear than 26 `Option<f32>`s.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Block {
    pub g: Vec<Code, MAX_CODES>,
    pub m: Vec<Code, MAX_CODES>,
    present: u32,
    values: [f32; 26],
}

/// Letters that carry values (everything else except G and M is unsupported), as a
/// mask with A = bit 0.
const VALUE_LETTERS: u32 = {
    let letters = b"FIJKLNPRSTXYZ";
    let mut mask = 0;
    let mut i = 0;
    while i < letters.len() {
        mask |= 1 << (letters[i] - b'A');
        i += 1;
    }
    mask
};

impl Block {
    /// Value word for `letter` (upper case), if present.
    pub fn get(&self, letter: u8) -> Option<f32> {
        let i = usize::from(letter.wrapping_sub(b'A'));
        let v = *self.values.get(i)?;
        (self.present >> i & 1 != 0).then_some(v)
    }

    /// Remove and return the value word for `letter` (used to track unused words).
    pub fn take(&mut self, letter: u8) -> Option<f32> {
        let v = self.get(letter)?;
        self.present &= !(1 << (letter - b'A'));
        Some(v)
    }

    /// Letters that still hold a value.
    pub fn any_value(&self) -> bool {
        self.present != 0
    }

    /// Parse a cleaned line (upper case, no spaces or comments).
    pub fn parse(line: &[u8]) -> Result<Block, Status> {
        let mut b = Block::default();
        b.parse_into(line)?;
        Ok(b)
    }

    /// [`Block::parse`] into an empty block (no block moved through a `Result`).
    pub fn parse_into(&mut self, line: &[u8]) -> Result<(), Status> {
        let b = self;
        let mut rest = line;
        while let Some((&letter, tail)) = rest.split_first() {
            if !letter.is_ascii_uppercase() {
                return Err(Status::ExpectedCommandLetter);
            }
            let (value, used) = read_number(tail)?;
            rest = tail.get(used..).unwrap_or(&[]);
            match letter {
                b'G' | b'M' => {
                    if value < 0.0 {
                        return Err(Status::CommandValueNotInteger);
                    }
                    let code = code_of(value)?;
                    let list = if letter == b'G' { &mut b.g } else { &mut b.m };
                    list.push(code).map_err(|_| Status::ModalGroupViolation)?;
                }
                _ if VALUE_LETTERS >> (letter - b'A') & 1 != 0 => {
                    let i = letter - b'A';
                    if b.present & (1 << i) != 0 {
                        return Err(Status::WordRepeated);
                    }
                    b.present |= 1 << i;
                    if let Some(slot) = b.values.get_mut(usize::from(i)) {
                        *slot = value;
                    }
                }
                _ => return Err(Status::UnsupportedCommand),
            }
        }
        Ok(())
    }
}

/// G/M value to code x 10; only whole numbers and one decimal (G28.1) are codes.
fn code_of(value: f32) -> Result<Code, Status> {
    if value > 999.0 {
        return Err(Status::UnsupportedCommand);
    }
    let hundredths = crate::decimal::to_u32(crate::fmath::round(value * 100.0));
    if !hundredths.is_multiple_of(10) {
        return Err(Status::CommandValueNotInteger);
    }
    Ok((hundredths / 10) as Code)
}

const POW10: [f32; 11] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];
/// Significant digits kept; further digits only scale (integer part) or are dropped.
const MAX_DIGITS: u32 = 9;

/// Read a number as Grbl does: optional sign, digits with at most one decimal point,
/// no exponent. Returns the value and the bytes used.
pub fn read_number(s: &[u8]) -> Result<(f32, usize), Status> {
    let mut i = 0;
    let mut negative = false;
    if let Some(&c) = s.first() {
        if c == b'-' || c == b'+' {
            negative = c == b'-';
            i = 1;
        }
    }
    let mut mantissa: u32 = 0;
    let mut sig = 0u32; // significant digits taken into the mantissa
    let mut any_digit = false;
    let mut seen_point = false;
    let mut frac_digits = 0usize; // decimals inside the mantissa
    let mut int_extra = 0usize; // integer digits beyond MAX_DIGITS
    while let Some(&c) = s.get(i) {
        match c {
            b'0'..=b'9' => {
                any_digit = true;
                let digit = u32::from(c - b'0');
                if sig < MAX_DIGITS && !(seen_point && frac_digits + 1 >= POW10.len()) {
                    mantissa = mantissa * 10 + digit;
                    if mantissa > 0 {
                        sig += 1;
                    }
                    if seen_point {
                        frac_digits += 1;
                    }
                } else if !seen_point {
                    int_extra += 1;
                }
            }
            b'.' if !seen_point => seen_point = true,
            _ => break,
        }
        i += 1;
    }
    if !any_digit {
        return Err(Status::BadNumberFormat);
    }
    let scale_up = POW10.get(int_extra).ok_or(Status::BadNumberFormat)?;
    let scale_down = POW10.get(frac_digits).ok_or(Status::BadNumberFormat)?;
    let v = mantissa as f32 * scale_up / scale_down;
    Ok((if negative { -v } else { v }, i))
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

    #[test]
    fn numbers_follow_grbl_rules() {
        assert_eq!(read_number(b"12.5X"), Ok((12.5, 4)));
        assert_eq!(read_number(b"-.5"), Ok((-0.5, 3)));
        assert_eq!(read_number(b"+3"), Ok((3.0, 2)));
        assert_eq!(read_number(b"1.2.3"), Ok((1.2, 3)));
        let (tiny, used) = read_number(b"0.000123456789").unwrap();
        assert_eq!(used, 14);
        assert!((tiny - 0.000_123_456_7).abs() < 1e-12);
        assert_eq!(read_number(b"0.000000000000001"), Ok((0.0, 17)));
        assert_eq!(read_number(b"-"), Err(Status::BadNumberFormat));
        assert_eq!(read_number(b"."), Err(Status::BadNumberFormat));
        assert_eq!(read_number(b"X"), Err(Status::BadNumberFormat));
        assert_eq!(
            read_number(b"99999999999999999999999"),
            Err(Status::BadNumberFormat)
        );
    }

    #[test]
    fn blocks_split_into_codes_and_words() {
        let b = Block::parse(b"G1G91.1X10Y-2F300M3").unwrap();
        assert_eq!(&b.g[..], &[10, 911]);
        assert_eq!(&b.m[..], &[30]);
        assert_eq!(b.get(b'X'), Some(10.0));
        assert_eq!(b.get(b'F'), Some(300.0));
        assert_eq!(b.get(b'Z'), None);
        assert_eq!(Block::parse(b"X1X2"), Err(Status::WordRepeated));
        assert_eq!(Block::parse(b"1"), Err(Status::ExpectedCommandLetter));
        assert_eq!(Block::parse(b"XA"), Err(Status::BadNumberFormat));
        assert_eq!(Block::parse(b"A1"), Err(Status::UnsupportedCommand));
        assert_eq!(Block::parse(b"G1.55"), Err(Status::CommandValueNotInteger));
        assert_eq!(Block::parse(b"G-1"), Err(Status::CommandValueNotInteger));
    }
}
