//! Small drawing pieces shared by the pages: fixed-width text cells, the title bar,
//! the progress bar, thin lines and the direction arrow, painted straight into the
//! [`FrameBuffer`] (no embedded-graphics pixel iterators or shapes in the firmware).
//!
//! Every widget paints all pixels of its cell each time (text with its background,
//! padded to a fixed width), so repainting an unchanged value changes no pixel and the
//! frame buffer stays clean: that is what makes "redraw only what changed" work without
//! a second buffer.

use super::fonts::{glyph, BODY_BITS, SMALL_BITS};
use super::framebuffer::FrameBuffer;

/// A pixel position (x, y).
pub type Px = (i32, i32);

/// Whether `b` starts a character in UTF-8 (is not a continuation byte).
fn starts_char(b: &u8) -> bool {
    (*b as i8) >= -0x40
}

/// A 1-pixel frame along the inside edge of the `w` x `h` rectangle at (x, y) (what a
/// 1-pixel stroke of the rectangle draws), as four solid fills.
pub fn frame(fb: &mut FrameBuffer, x: i32, y: i32, w: i32, h: i32, on: bool) {
    if w <= 0 || h <= 0 {
        return;
    }
    fb.fill(x, y, w, 1, on);
    fb.fill(x, y + h - 1, w, 1, on);
    fb.fill(x, y, 1, h, on);
    fb.fill(x + w - 1, y, 1, h, on);
}

/// Where and how a text cell is painted, packed in one word so that a call passes it
/// in a single register: top-left x and y, width in characters, font, inverse, alignment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell(u32);

impl Cell {
    const SMALL: u32 = 1 << 24;
    const INVERSE: u32 = 1 << 25;
    const RIGHT: u32 = 1 << 26;

    /// `chars` characters of the body font, top-left at (x, y) (on screen: 0..=255).
    pub const fn at(x: i32, y: i32, chars: usize) -> Cell {
        Cell((x as u32 & 0xFF) | (y as u32 & 0xFF) << 8 | (chars as u32 & 0xFF) << 16)
    }
    /// In the small font instead.
    pub const fn small(self) -> Cell {
        Cell(self.0 | Self::SMALL)
    }
    /// Light on dark if `on`.
    pub const fn inverse(self, on: bool) -> Cell {
        Cell(if on { self.0 | Self::INVERSE } else { self.0 })
    }
    /// Right-aligned in the cell.
    pub const fn right(self) -> Cell {
        Cell(self.0 | Self::RIGHT)
    }
}

/// Paint the text `s` (UTF-8 bytes) in the text cell `c`: exactly `c`'s width in
/// characters, truncated if longer (keeping the end if right-aligned), padded with
/// background if shorter.
///
/// The glyphs are copied straight out of the font bitmap, each character cell painted
/// whole (glyph and background) like embedded-graphics' `MonoTextStyle` with a
/// background colour does, pixel for pixel; padding is painted as spaces (blank glyphs).
pub fn put(fb: &mut FrameBuffer, c: Cell, s: &[u8]) {
    let c = c.0;
    let (bits, gw, h): (&[u8], u32, u32) = if c & Cell::SMALL != 0 {
        (&SMALL_BITS, 5, 8)
    } else {
        (&BODY_BITS, 6, 10)
    };
    let inverse = c & Cell::INVERSE != 0;
    let right = c & Cell::RIGHT != 0;
    let (x0, y0) = ((c & 0xFF) as i32, (c >> 8 & 0xFF) as i32);
    let chars = (c >> 16 & 0xFF) as usize;
    // Characters are counted and looked up by their first byte: exact for any &str.
    let count = s.iter().filter(|b| starts_char(b)).count();
    let n = count.min(chars);
    let pad = chars - n;
    let mut text = s
        .iter()
        .copied()
        .filter(starts_char)
        .skip(if right { count - n } else { 0 });
    // Where each slot's glyph starts in the bitmap (its rows follow each other from
    // there). Slots from the 26th on start past the screen's right edge (x0 >= 0,
    // glyphs 5 or more wide): they paint nothing and are not looked up.
    let mut starts = [0u16; SLOTS_ON_SCREEN];
    for (slot, start) in starts.iter_mut().enumerate().take(chars) {
        // Right-aligned: the padding first; otherwise it follows the text.
        let lead = if right && slot < pad {
            b' '
        } else {
            text.next().unwrap_or(b' ')
        };
        *start = (glyph(lead) * gw * h) as u16;
    }
    let slots = starts.get(..chars).unwrap_or(&starts);
    // Row by row, the glyph rows side by side, painted up to 24 pixels at a time.
    let glyph_mask = !(u32::MAX >> gw);
    let invert = if inverse { u32::MAX } else { 0 };
    for row in 0..h {
        let y = y0 + row as i32;
        let (mut run, mut run_n, mut run_x) = (0u32, 0u32, x0);
        for &start in slots {
            let i = u32::from(start) + row * gw;
            let at = (i / 8) as usize;
            let two = u32::from(bits.get(at).copied().unwrap_or(0)) << 24
                | u32::from(bits.get(at + 1).copied().unwrap_or(0)) << 16;
            if run_n + gw > 24 {
                fb.set_bits(run_x, y, run ^ invert, run_n);
                run_x += run_n as i32;
                (run, run_n) = (0, 0);
            }
            run |= ((two << (i % 8)) & glyph_mask) >> run_n;
            run_n += gw;
        }
        fb.set_bits(run_x, y, run ^ invert, run_n);
    }
}

/// Character slots that can start on screen (the narrow font's 5 pixels into 128).
const SLOTS_ON_SCREEN: usize = 26;

/// The inverted title bar (rows 0..=9): title on the left, `right` on the right.
pub fn title_bar(fb: &mut FrameBuffer, title: &[u8], right: &[u8]) {
    const CHARS: usize = 21;
    let rn = right.iter().filter(|b| starts_char(b)).count().min(10);
    fb.fill(0, 0, 1, 10, true);
    fb.fill(127, 0, 1, 10, true);
    put(fb, Cell::at(1, 0, CHARS - rn).inverse(true), title);
    put(
        fb,
        Cell::at(1 + ((CHARS - rn) * 6) as i32, 0, rn)
            .inverse(true)
            .right(),
        right,
    );
}

/// The bottom line (rows 54..=63): a hint, or a message shown inverted.
pub fn bottom_line(fb: &mut FrameBuffer, hint: &[u8], message: Option<&[u8]>) {
    let inverse = message.is_some();
    fb.fill(0, 54, 128, 1, false);
    fb.fill(0, 55, 3, 9, inverse);
    let text = message.unwrap_or(hint);
    put(fb, Cell::at(3, 55, 25).small().inverse(inverse), text);
    // 5x8 leaves the last row of the line free: keep it painted.
    fb.fill(0, 63, 128, 1, inverse);
}

/// A horizontal progress bar with a frame in the `w` x `h` box at (x, y); `frac` in
/// 0..=1.
pub fn progress(fb: &mut FrameBuffer, x: i32, y: i32, w: i32, h: i32, frac: f32) {
    frame(fb, x, y, w, h, true);
    let inner_w = w - 4;
    let f = if frac.is_finite() {
        frac.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let filled = crate::decimal::round_i32(inner_w as f32 * f);
    fb.fill(x + 2, y + 2, filled, h - 4, true);
    fb.fill(x + 2 + filled, y + 2, inner_w - filled, h - 4, false);
    // The 1-pixel gap between frame and bar.
    frame(fb, x + 1, y + 1, w - 2, h - 2, false);
}

/// A 1-pixel line from `a` to `b` (Bresenham), both ends included.
pub fn line(fb: &mut FrameBuffer, a: Px, b: Px) {
    let (dx, dy) = ((b.0 - a.0).abs(), -(b.1 - a.1).abs());
    let sx = if a.0 < b.0 { 1 } else { -1 };
    let sy = if a.1 < b.1 { 1 } else { -1 };
    let mut p = a;
    let mut err = dx + dy;
    loop {
        fb.set(p.0, p.1, true);
        if p == b {
            return;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            p.0 += sx;
        }
        if e2 <= dx {
            err += dx;
            p.1 += sy;
        }
    }
}

/// `v / unit` (or `v / (unit sqrt 2)` on a `diagonal`) rounded half away from zero:
/// the count of m >= 1 with s v^2 >= ((2m - 1) unit)^2, s = 4 (or 2). In u32 for
/// |v| <= 32,000 and unit <= 800 (the arrow up to 40 pixels).
fn round_unit(v: i32, unit: i32, diagonal: bool) -> i32 {
    let sq = (v.unsigned_abs().pow(2)) << (2 - diagonal as u32);
    let mut m = 0;
    while sq >= ((2 * m + 1) * unit as u32).pow(2) {
        m += 1;
    }
    if v < 0 {
        -(m as i32)
    } else {
        m as i32
    }
}

/// A direction arrow for (dx, dy) signs, fitted in the `size` x `size` square at
/// (x, y) (Y up; `size` at most 40): a 3-pixel shaft and a head, filled when `solid`
/// (moving) or outlined (stopped). A zero direction draws a small square (no direction
/// yet). Built from 1-pixel lines only.
///
/// In integers: with r = size / 2 - 2 and the head's fan of `steps` = ceil(2.2 r) lines
/// each side, every length (r, r / 10, half-pixel shaft offsets, 0.55 r k / steps) is a
/// whole number of 1 / (20 steps) pixel units, and a point is rounded once, half away
/// from zero, along the unit direction (length 1, or sqrt 2 on a diagonal, where no
/// point falls on a half). The same pixels as the float arrow it replaced (checked in
/// the tests in every direction and style).
pub fn arrow(fb: &mut FrameBuffer, x: i32, y: i32, size: i32, dir: [i8; 2], solid: bool) {
    let c = (x + (size - 1) / 2, y + (size - 1) / 2);
    if dir == [0, 0] {
        // A 2-pixel stroke centred on a 9x9 square: rings of 11x11 and 9x9.
        frame(fb, c.0 - 5, c.1 - 5, 11, 11, true);
        return frame(fb, c.0 - 4, c.1 - 4, 9, 9, true);
    }
    let (dx, dy) = (i32::from(dir[0]), -i32::from(dir[1]));
    let r = size / 2 - 2;
    let steps = (22 * r + 9) / 10;
    let unit = 20 * steps;
    let diagonal = dx != 0 && dy != 0;
    let at = |along: i32, across: i32| {
        (
            c.0 + round_unit(dx * along - dy * across, unit, diagonal),
            c.1 + round_unit(dy * along + dx * across, unit, diagonal),
        )
    };
    let (len, base, half) = (20 * r * steps, 2 * r * steps, 11 * r * steps);
    // Shaft: parallel lines half a pixel apart leave no gaps on diagonals.
    for k in -3..4 {
        let o = k * 10 * steps;
        line(fb, at(-len, o), at(base, o));
    }
    let tip = at(len, 0);
    if solid {
        // Fill the head with a fan of lines from the tip.
        for k in -steps..steps + 1 {
            line(fb, tip, at(base, 11 * r * k));
        }
    } else {
        let (b1, b2) = (at(base, half), at(base, -half));
        line(fb, tip, b1);
        line(fb, b1, b2);
        line(fb, b2, tip);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::screens::fonts::{BODY, SMALL};
    use embedded_graphics::pixelcolor::BinaryColor;
    use embedded_graphics::prelude::*;
    use embedded_graphics::primitives::Rectangle;

    const ON: BinaryColor = BinaryColor::On;
    const OFF: BinaryColor = BinaryColor::Off;

    /// The text painter gives exactly what embedded-graphics' MonoTextStyle with a
    /// background draws for the shown characters, plus the background padding.
    #[test]
    fn put_paints_like_embedded_graphics_text() {
        use embedded_graphics::mono_font::MonoTextStyleBuilder;
        use embedded_graphics::text::{Baseline, Text};
        let cases = [
            ("Hello, -12.5 mm", 20, false, false, false),
            ("\u{e9}\u{20ac}x?\u{4e2d}~", 6, true, true, false),
            ("truncated text here", 5, false, true, true),
            ("ab", 7, true, false, true),
            ("", 3, false, true, false),
        ];
        for (s, chars, small, inverse, right) in cases {
            let mut c = Cell::at(3, 7, chars).inverse(inverse);
            if small {
                c = c.small();
            }
            if right {
                c = c.right();
            }
            let mut ours = FrameBuffer::new();
            put(&mut ours, c, s.as_bytes());
            let font = if small { &SMALL } else { &BODY };
            let (fg, bg) = if inverse { (OFF, ON) } else { (ON, OFF) };
            let style = MonoTextStyleBuilder::new()
                .font(font)
                .text_color(fg)
                .background_color(bg)
                .build();
            // Only the fonts' stored characters have their own glyph, the others are
            // '?' (embedded-graphics does that itself for non-ASCII ones).
            let stored = |c: char| !c.is_ascii() || glyph(c as u8) != glyph(b'?');
            let all: std::vec::Vec<char> =
                s.chars().map(|c| if stored(c) { c } else { '?' }).collect();
            let n = all.len().min(chars);
            let shown: std::string::String = if right {
                all[all.len() - n..].iter().collect()
            } else {
                all[..n].iter().collect()
            };
            let cw = font.character_size.width as i32;
            let pad = (chars - n) as i32;
            let (text_x, pad_x) = if right {
                (3 + pad * cw, 3)
            } else {
                (3, 3 + n as i32 * cw)
            };
            let mut reference = FrameBuffer::new();
            Text::with_baseline(&shown, Point::new(text_x, 7), style, Baseline::Top)
                .draw(&mut reference)
                .unwrap();
            let blank = Size::new((pad * cw) as u32, font.character_size.height);
            reference
                .fill_solid(&Rectangle::new(Point::new(pad_x, 7), blank), bg)
                .unwrap();
            assert!(ours.bytes() == reference.bytes(), "{s:?}");
        }
    }

    /// The glyph painter as first written, a pixel at a time: the reference for the
    /// row-at-once painter at every bit alignment and clipped at the screen's edges.
    fn put_by_pixel(fb: &mut FrameBuffer, x0: i32, y0: i32, small: bool, inverse: bool, s: &[u8]) {
        let (bits, gw, h): (&[u8], u32, u32) = if small {
            (&SMALL_BITS, 5, 8)
        } else {
            (&BODY_BITS, 6, 10)
        };
        let mut x = x0;
        for &lead in s {
            let mut i = glyph(lead) * gw * h;
            for y in y0..y0 + h as i32 {
                for dx in 0..gw {
                    let b = (i + dx) as usize;
                    let on = bits.get(b / 8).is_some_and(|v| v & (0x80 >> (b % 8)) != 0);
                    fb.set(x + dx as i32, y, on != inverse);
                }
                i += gw;
            }
            x += gw as i32;
        }
    }

    #[test]
    fn glyph_rows_paint_like_single_pixels_at_every_alignment() {
        let short = b"Xy-0.9~|@#{}";
        // Wider than the screen: the slots past its edge paint nothing.
        let long = b"abcdefghijklmnopqrstuvwxyz0123";
        for small in [false, true] {
            for inverse in [false, true] {
                let cases = (0..12).map(|x| (x, 3, &short[..])).chain([
                    (120, 0, &short[..]),
                    (97, 58, &short[..]),
                    (3, 20, &long[..]),
                    (0, 30, &long[..]),
                ]);
                for (x, y, text) in cases {
                    // Over a busy background, so that every pixel is really painted.
                    let mut ours = FrameBuffer::new();
                    for i in 0..64 {
                        ours.fill(2 * i, 0, 1, 64, true);
                    }
                    ours.mark_clean();
                    let mut theirs = ours.clone();
                    let mut c = Cell::at(x, y, text.len()).inverse(inverse);
                    if small {
                        c = c.small();
                    }
                    put(&mut ours, c, text);
                    put_by_pixel(&mut theirs, x, y, small, inverse, text);
                    assert_eq!(ours, theirs, "x {x} y {y} small {small} inverse {inverse}");
                }
            }
        }
    }

    /// The arrow as first written (two rounding expressions per point, libm), kept to
    /// check that the shared rounding helper draws the same pixels.
    fn old_arrow(d: &mut FrameBuffer, area: Rectangle, dir: [i8; 2], solid: bool) {
        let c = area.center();
        if dir == [0, 0] {
            // A 2-pixel stroke centred on a 9x9 square: rings of 11x11 and 9x9.
            for size in [11, 9] {
                let r = Rectangle::with_center(c, Size::new(size, size));
                let (p, s) = (r.top_left, r.size);
                frame(d, p.x, p.y, s.width as i32, s.height as i32, true);
            }
            return;
        }
        let r = (area.size.width.min(area.size.height) / 2) as f32 - 2.0;
        let (dx, dy) = (dir[0] as f32, -(dir[1] as f32));
        let n = libm::hypotf(dx, dy);
        let (ux, uy) = (dx / n, dy / n);
        let at = |along: f32, across: f32| {
            (
                c.x + libm::roundf(ux * along - uy * across) as i32,
                c.y + libm::roundf(uy * along + ux * across) as i32,
            )
        };
        let base = r * 0.1;
        let half = r * 0.55;
        // Shaft: parallel lines half a pixel apart leave no gaps on diagonals.
        for k in -3..=3 {
            let o = k as f32 * 0.5;
            line(d, at(-r, o), at(base, o));
        }
        let tip = at(r, 0.0);
        if solid {
            // Fill the head with a fan of lines from the tip.
            let steps = libm::ceilf(half * 4.0) as i32;
            for k in -steps..=steps {
                let across = half * k as f32 / steps as f32;
                line(d, tip, at(base, across));
            }
        } else {
            let (b1, b2) = (at(base, half), at(base, -half));
            for (p, q) in [(tip, b1), (b1, b2), (b2, tip)] {
                line(d, p, q);
            }
        }
    }

    #[test]
    fn arrow_is_unchanged_in_every_direction_and_style() {
        // 40 is the jog page's; the others check the integer scaling.
        for size in [40, 12, 21, 30, 33, 39] {
            let area = Rectangle::new(Point::new(4, 0), Size::new(size, size));
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for solid in [false, true] {
                        let (mut ours, mut first) = (FrameBuffer::new(), FrameBuffer::new());
                        arrow(&mut ours, 4, 0, size as i32, [dx, dy], solid);
                        old_arrow(&mut first, area, [dx, dy], solid);
                        assert!(ours.bytes() == first.bytes(), "{size} {dx} {dy} {solid}");
                    }
                }
            }
        }
    }

    /// Characters are looked up by their first byte: a stored ASCII character is its
    /// own glyph (checked pixel for pixel in the fonts' tests), anything else the '?'
    /// that embedded-graphics' mapping also gives non-ASCII characters.
    #[test]
    fn glyph_lookup_matches_the_fonts_mapping() {
        let question = glyph(b'?');
        for font in [&BODY, &SMALL] {
            for c in (0..0x300)
                .filter_map(char::from_u32)
                .chain(['€', '中', '😀'])
            {
                let mut buf = [0; 4];
                let utf8 = c.encode_utf8(&mut buf).as_bytes();
                let lead = utf8[0];
                if !c.is_ascii() || c < ' ' {
                    assert_eq!(font.glyph_mapping.index(c), font.glyph_mapping.index('?'));
                    assert_eq!(glyph(lead), question, "{c:?}");
                }
                assert_eq!(utf8.iter().filter(|b| starts_char(b)).count(), 1, "{c:?}");
            }
        }
    }

    #[test]
    fn thin_line_covers_both_ends_with_one_pixel_per_major_step() {
        for (a, b) in [
            (Point::new(3, 4), Point::new(40, 17)),
            (Point::new(40, 17), Point::new(3, 4)),
            (Point::new(10, 50), Point::new(12, 5)),
            (Point::new(7, 7), Point::new(7, 7)),
        ] {
            let mut fb = FrameBuffer::new();
            line(&mut fb, (a.x, a.y), (b.x, b.y));
            let on = fb.bytes().iter().map(|b| b.count_ones()).sum::<u32>();
            let major = (b.x - a.x).abs().max((b.y - a.y).abs()) as u32 + 1;
            assert_eq!(on, major, "{a:?} -> {b:?}");
            assert!(fb.pixel(a.x as usize, a.y as usize) && fb.pixel(b.x as usize, b.y as usize));
        }
    }
}
