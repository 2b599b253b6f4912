//! [`Text`]: a short string in a fixed array, `Copy` so that the pages and the whole
//! [`super::Hmi`] are plain data: the firmware copies the HMI out of its lock on every
//! LCD refresh, one block copy instead of a clone per field.

use core::fmt;
use core::ops::Deref;

/// Up to `N` bytes of UTF-8 text.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Text<const N: usize> {
    len: u8,
    buf: [u8; N],
}

impl<const N: usize> Default for Text<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Text<N> {
    /// The empty text (`N` must be at most 255).
    pub const fn new() -> Self {
        Text {
            len: 0,
            buf: [0; N],
        }
    }

    /// The longest prefix of `s` that fits, cut at a character boundary.
    pub fn truncated(s: &str) -> Self {
        let mut end = s.len().min(N);
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        let mut t = Self::new();
        let _ = t.push_str(s.get(..end).unwrap_or(""));
        t
    }

    pub fn as_str(&self) -> &str {
        let bytes = self.buf.get(..usize::from(self.len)).unwrap_or(&[]);
        core::str::from_utf8(bytes).unwrap_or("")
    }

    pub fn as_bytes(&self) -> &[u8] {
        self.bytes()
    }

    /// Length in bytes.
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Keep the first `len` bytes (callers cut only at character boundaries).
    pub fn truncate(&mut self, len: usize) {
        // A boundary: not a UTF-8 continuation byte.
        let boundary = self.buf.get(len).is_some_and(|&b| (b as i8) >= -0x40);
        if len < usize::from(self.len) && boundary {
            self.len = len as u8;
        }
    }

    /// The text's bytes (UTF-8), without re-checking them.
    pub fn bytes(&self) -> &[u8] {
        self.buf.get(..usize::from(self.len)).unwrap_or(&[])
    }

    /// Append `s` whole, or change nothing and return false if it does not fit.
    pub fn push_str(&mut self, s: &str) -> bool {
        append(&mut self.buf, &mut self.len, s.as_bytes())
    }

    /// Append `c`; false (and unchanged) if it does not fit.
    pub fn push(&mut self, c: char) -> bool {
        self.push_str(c.encode_utf8(&mut [0; 4]))
    }

    /// Append the whole of `t`, or change nothing and return false if it does not fit.
    pub fn push_text<const M: usize>(&mut self, t: &Text<M>) -> bool {
        append(&mut self.buf, &mut self.len, t.bytes())
    }

    /// Append the ASCII byte `b` (anything else is refused, keeping the text UTF-8).
    pub fn push_ascii(&mut self, b: u8) -> bool {
        b.is_ascii() && append(&mut self.buf, &mut self.len, &[b])
    }

    /// Append [`super::fixed::format`]`(v, decimals)`; false if it does not fit.
    pub fn push_fixed(&mut self, v: f32, decimals: u8) -> bool {
        let num = super::fixed::scaled(v, decimals);
        self.push_number(num, decimals.min(3), 0)
    }

    /// Append the unsigned integer `n` right-aligned in `width` characters.
    pub fn push_uint(&mut self, n: u32, width: usize) -> bool {
        self.push_number(Some((false, n)), 0, width)
    }

    /// Append `num` with `decimals` digits, right-aligned in `width` characters (the
    /// screens' number format, `hmi::fixed::append_number`); false (and unchanged) if
    /// it does not fit.
    pub fn push_number(&mut self, num: super::fixed::Number, decimals: u8, width: usize) -> bool {
        super::fixed::append_number(&mut self.buf, &mut self.len, num, decimals, width)
    }

    /// Remove the last character; false if the text was empty.
    pub fn pop(&mut self) -> bool {
        // Back to the last byte that starts a character (not a UTF-8 continuation).
        match self.bytes().iter().rposition(|&b| (b as i8) >= -0x40) {
            Some(end) => {
                self.len = end as u8;
                true
            }
            None => false,
        }
    }

    pub fn clear(&mut self) {
        self.len = 0;
    }
}

/// The work of [`Text::push_str`] for every capacity: append `s` whole to the first
/// `len` bytes of `buf`, or change nothing.
pub(super) fn append(buf: &mut [u8], len: &mut u8, s: &[u8]) -> bool {
    let at = usize::from(*len);
    let end = at + s.len();
    match buf.get_mut(at..end) {
        Some(dst) if end <= usize::from(u8::MAX) => {
            // Byte by byte: `copy_from_slice` would keep a length-mismatch panic the
            // compiler cannot rule out.
            for (d, &b) in dst.iter_mut().zip(s) {
                *d = b;
            }
            *len = end as u8;
            true
        }
        _ => false,
    }
}

impl<const N: usize> Deref for Text<N> {
    type Target = str;
    fn deref(&self) -> &str {
        self.as_str()
    }
}

impl<const N: usize> fmt::Debug for Text<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl<const N: usize> PartialEq<&str> for Text<N> {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_pop_and_truncation_keep_whole_characters() {
        let mut t: Text<4> = Text::new();
        assert!(t.push_str("ab"));
        assert!(t.push('é'));
        assert_eq!(t.as_str(), "abé");
        assert!(!t.push('c'), "full");
        assert!(t.pop());
        assert_eq!(t, "ab");
        assert!(t.pop());
        assert_eq!(t, "a");
        t.clear();
        assert!(!t.pop());
        assert_eq!(Text::<4>::truncated("xyzé").as_str(), "xyz");
        assert_eq!(Text::<5>::truncated("xyzé").as_str(), "xyzé");
    }
}
