//! Small drawing pieces shared by the pages: fixed-width text cells, the title bar,
//! the progress bar and the direction arrow.
//!
//! Every widget paints all pixels of its cell each time (text with its background,
//! padded to a fixed width), so repainting an unchanged value changes no pixel and the
//! frame buffer stays clean: that is what makes "redraw only what changed" work without
//! a second buffer.

use crate::fmath;
use embedded_graphics::image::GetPixel;
use embedded_graphics::image::ImageRaw;
use embedded_graphics::mono_font::MonoFont;
use embedded_graphics::pixelcolor::BinaryColor;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::Rectangle;

use super::fonts::{BODY, SMALL};

const ON: BinaryColor = BinaryColor::On;
const OFF: BinaryColor = BinaryColor::Off;

/// What the text painter needs of a font: its bitmap and cell size. Taken out of the
/// `MonoFont` constants at compile time, so the fonts' dynamic glyph-mapping objects
/// never reach the firmware.
pub struct Glyphs {
    image: ImageRaw<'static, BinaryColor>,
    size: Size,
    spacing: u32,
}

const fn glyphs(font: &MonoFont<'static>) -> Glyphs {
    Glyphs {
        image: font.image,
        size: font.character_size,
        spacing: font.character_spacing,
    }
}

static BODY_GLYPHS: Glyphs = glyphs(&BODY);
static SMALL_GLYPHS: Glyphs = glyphs(&SMALL);

/// Glyph index, in the screens' fonts, of the character whose UTF-8 encoding starts
/// with byte `lead`. Both fonts are embedded-graphics' ASCII fonts: ' '..='\u{7f}' in
/// order, anything else shown as '?'. The same as the fonts' `glyph_mapping` (checked in
/// the tests) without its dynamic, string-walking lookup or UTF-8 decoding.
fn ascii_glyph(lead: u8) -> u32 {
    if (b' '..=0x7f).contains(&lead) {
        u32::from(lead) - 32
    } else {
        u32::from(b'?') - 32
    }
}

/// Whether `b` starts a character in UTF-8 (is not a continuation byte).
fn starts_char(b: &u8) -> bool {
    (*b as i8) >= -0x40
}

/// A 1-pixel frame along the inside edge of `r` (what a 1-pixel stroke of the
/// rectangle draws), as four solid fills.
pub fn frame<D>(d: &mut D, r: Rectangle, color: BinaryColor) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    let (tl, w, h) = (r.top_left, r.size.width, r.size.height);
    if w == 0 || h == 0 {
        return Ok(());
    }
    for &(p, s) in [
        (tl, Size::new(w, 1)),
        (tl + Point::new(0, h as i32 - 1), Size::new(w, 1)),
        (tl, Size::new(1, h)),
        (tl + Point::new(w as i32 - 1, 0), Size::new(1, h)),
    ]
    .iter()
    {
        d.fill_solid(&Rectangle::new(p, s), color)?;
    }
    Ok(())
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
    fn right_aligned(self) -> bool {
        self.0 & Self::RIGHT != 0
    }
    fn pos(self) -> Point {
        Point::new((self.0 & 0xFF) as i32, (self.0 >> 8 & 0xFF) as i32)
    }
    fn chars(self) -> usize {
        (self.0 >> 16 & 0xFF) as usize
    }
    fn font(self) -> &'static Glyphs {
        if self.0 & Self::SMALL != 0 {
            &SMALL_GLYPHS
        } else {
            &BODY_GLYPHS
        }
    }
    fn inverted(self) -> bool {
        self.0 & Self::INVERSE != 0
    }
}

/// Paint `s` in the text cell `c`: exactly `c`'s width in characters, truncated if
/// longer (keeping the end if right-aligned), padded with background if shorter.
///
/// The glyphs are copied straight out of the font bitmap, each character cell painted
/// whole (glyph and background) like embedded-graphics' `MonoTextStyle` with a
/// background colour does, pixel for pixel, without its text layout machinery.
pub fn put<D>(d: &mut D, c: Cell, s: &str) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    let font = c.font();
    let (fg, bg) = if c.inverted() { (OFF, ON) } else { (ON, OFF) };
    let gw = font.size.width;
    let h = font.size.height;
    let cw = gw + font.spacing;
    let per_row = (font.image.size().width / gw.max(1)).max(1);
    // Characters are counted and looked up by their first byte: exact for any &str.
    let count = s.bytes().filter(starts_char).count();
    let n = count.min(c.chars());
    let pad = (c.chars() - n) as u32;
    let right = c.right_aligned();
    let Point { mut x, y } = c.pos();
    let blank = Size::new(pad * cw, h);
    if right && pad > 0 {
        d.fill_solid(&Rectangle::new(Point::new(x, y), blank), bg)?;
        x += blank.width as i32;
    }
    let shown = s.bytes().filter(starts_char);
    for lead in shown.skip(if right { count - n } else { 0 }).take(n) {
        let g = ascii_glyph(lead);
        let origin = Point::new(((g % per_row) * gw) as i32, ((g / per_row) * h) as i32);
        let at = Point::new(x, y);
        let pixels = (0..cw * h).map(move |i| {
            let g = Point::new((i % cw) as i32, (i / cw) as i32);
            let on = g.x < gw as i32 && font.image.pixel(origin + g) == Some(ON);
            Pixel(at + g, if on { fg } else { bg })
        });
        d.draw_iter(pixels)?;
        x += cw as i32;
    }
    if !right && pad > 0 {
        d.fill_solid(&Rectangle::new(Point::new(x, y), blank), bg)?;
    }
    Ok(())
}

/// The inverted title bar (rows 0..=9): title on the left, `right` on the right.
pub fn title_bar<D>(d: &mut D, title: &str, right: &str) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    const CHARS: usize = 21;
    let rn = right.chars().count().min(10);
    d.fill_solid(&Rectangle::new(Point::zero(), Size::new(1, 10)), ON)?;
    d.fill_solid(&Rectangle::new(Point::new(127, 0), Size::new(1, 10)), ON)?;
    put(d, Cell::at(1, 0, CHARS - rn).inverse(true), title)?;
    put(
        d,
        Cell::at(1 + ((CHARS - rn) * 6) as i32, 0, rn)
            .inverse(true)
            .right(),
        right,
    )
}

/// The bottom line (rows 54..=63): a hint, or a message shown inverted.
pub fn bottom_line<D>(d: &mut D, hint: &str, message: Option<&str>) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    let inverse = message.is_some();
    let bg = if inverse { ON } else { OFF };
    d.fill_solid(&Rectangle::new(Point::new(0, 54), Size::new(128, 1)), OFF)?;
    d.fill_solid(&Rectangle::new(Point::new(0, 55), Size::new(3, 9)), bg)?;
    put(
        d,
        Cell::at(3, 55, 25).small().inverse(inverse),
        message.unwrap_or(hint),
    )?;
    // 5x8 leaves the last row of the line free: keep it painted.
    d.fill_solid(&Rectangle::new(Point::new(0, 63), Size::new(128, 1)), bg)
}

/// A horizontal progress bar with a frame; `frac` in 0..=1.
pub fn progress<D>(d: &mut D, area: Rectangle, frac: f32) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    frame(d, area, ON)?;
    let inner_w = area.size.width.saturating_sub(4);
    let h = area.size.height.saturating_sub(4);
    let f = if frac.is_finite() {
        frac.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let filled = fmath::round(inner_w as f32 * f) as u32;
    let tl = area.top_left + Point::new(2, 2);
    d.fill_solid(&Rectangle::new(tl, Size::new(filled, h)), ON)?;
    d.fill_solid(
        &Rectangle::new(
            tl + Point::new(filled as i32, 0),
            Size::new(inner_w - filled, h),
        ),
        OFF,
    )?;
    // The 1-pixel gap between frame and bar.
    let gap = Rectangle::new(
        area.top_left + Point::new(1, 1),
        area.size - Size::new(2, 2),
    );
    frame(d, gap, OFF)
}

/// A 1-pixel line from `a` to `b` (Bresenham). embedded-graphics' styled `Line` carries
/// the thick-line machinery for any stroke width; the screens only need thin lines.
pub fn line<D>(d: &mut D, a: Point, b: Point) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    let (dx, dy) = ((b.x - a.x).abs(), -(b.y - a.y).abs());
    let (sx, sy) = (
        if a.x < b.x { 1 } else { -1 },
        if a.y < b.y { 1 } else { -1 },
    );
    let mut p = a;
    let mut err = dx + dy;
    let mut done = false;
    let pixels = core::iter::from_fn(move || {
        if done {
            return None;
        }
        let here = p;
        if here == b {
            done = true;
        } else {
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                p.x += sx;
            }
            if e2 <= dx {
                err += dx;
                p.y += sy;
            }
        }
        Some(Pixel(here, ON))
    });
    d.draw_iter(pixels)
}

/// A direction arrow for (dx, dy) signs, fitted in a square `area` (Y up): a 3-pixel
/// shaft and a head, filled when `solid` (moving) or outlined (stopped). A zero
/// direction draws a small square (no direction yet). Built from 1-pixel lines only, so
/// embedded-graphics' thick-line and triangle fillers stay out of the firmware.
pub fn arrow<D>(d: &mut D, area: Rectangle, dir: [i8; 2], solid: bool) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    let c = area.center();
    if dir == [0, 0] {
        // A 2-pixel stroke centred on a 9x9 square: rings of 11x11 and 9x9.
        frame(d, Rectangle::with_center(c, Size::new(11, 11)), ON)?;
        return frame(d, Rectangle::with_center(c, Size::new(9, 9)), ON);
    }
    let r = (area.size.width.min(area.size.height) / 2) as f32 - 2.0;
    let (dx, dy) = (dir[0] as f32, -(dir[1] as f32));
    let n = fmath::hypot(dx, dy);
    let (ux, uy) = (dx / n, dy / n);
    // One rounding helper for both coordinates: u*along - v*across, rounded. For y,
    // (v = -ux) gives uy*along + ux*across bit for bit (negation is exact).
    fn rot(u: f32, v: f32, along: f32, across: f32) -> i32 {
        fmath::round(u * along - v * across) as i32
    }
    let at = |along: f32, across: f32| {
        Point::new(
            c.x + rot(ux, uy, along, across),
            c.y + rot(uy, -ux, along, across),
        )
    };
    let base = r * 0.1;
    let half = r * 0.55;
    // Shaft: parallel lines half a pixel apart leave no gaps on diagonals.
    for k in -3..4 {
        let o = k as f32 * 0.5;
        line(d, at(-r, o), at(base, o))?;
    }
    let tip = at(r, 0.0);
    if solid {
        // Fill the head with a fan of lines from the tip.
        let steps = fmath::ceil(half * 4.0) as i32;
        for k in -steps..steps + 1 {
            let across = half * k as f32 / steps as f32;
            line(d, tip, at(base, across))?;
        }
        Ok(())
    } else {
        let (b1, b2) = (at(base, half), at(base, -half));
        for &(p, q) in [(tip, b1), (b1, b2), (b2, tip)].iter() {
            line(d, p, q)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::screens::framebuffer::FrameBuffer;

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
            put(&mut ours, c, s).unwrap();
            let font = if small { &SMALL } else { &BODY };
            let (fg, bg) = if inverse { (OFF, ON) } else { (ON, OFF) };
            let style = MonoTextStyleBuilder::new()
                .font(font)
                .text_color(fg)
                .background_color(bg)
                .build();
            let all: std::vec::Vec<char> = s.chars().collect();
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

    /// The arrow as first written (two rounding expressions per point), kept to check
    /// that the shared rounding helper draws the same pixels.
    fn old_arrow<D>(d: &mut D, area: Rectangle, dir: [i8; 2], solid: bool) -> Result<(), D::Error>
    where
        D: DrawTarget<Color = BinaryColor>,
    {
        let c = area.center();
        if dir == [0, 0] {
            // A 2-pixel stroke centred on a 9x9 square: rings of 11x11 and 9x9.
            frame(d, Rectangle::with_center(c, Size::new(11, 11)), ON)?;
            return frame(d, Rectangle::with_center(c, Size::new(9, 9)), ON);
        }
        let r = (area.size.width.min(area.size.height) / 2) as f32 - 2.0;
        let (dx, dy) = (dir[0] as f32, -(dir[1] as f32));
        let n = libm::hypotf(dx, dy);
        let (ux, uy) = (dx / n, dy / n);
        let at = |along: f32, across: f32| {
            Point::new(
                c.x + libm::roundf(ux * along - uy * across) as i32,
                c.y + libm::roundf(uy * along + ux * across) as i32,
            )
        };
        let base = r * 0.1;
        let half = r * 0.55;
        // Shaft: parallel lines half a pixel apart leave no gaps on diagonals.
        for k in -3..=3 {
            let o = k as f32 * 0.5;
            line(d, at(-r, o), at(base, o))?;
        }
        let tip = at(r, 0.0);
        if solid {
            // Fill the head with a fan of lines from the tip.
            let steps = libm::ceilf(half * 4.0) as i32;
            for k in -steps..=steps {
                let across = half * k as f32 / steps as f32;
                line(d, tip, at(base, across))?;
            }
            Ok(())
        } else {
            let (b1, b2) = (at(base, half), at(base, -half));
            for (p, q) in [(tip, b1), (b1, b2), (b2, tip)] {
                line(d, p, q)?;
            }
            Ok(())
        }
    }

    #[test]
    fn arrow_is_unchanged_in_every_direction_and_style() {
        let area = Rectangle::new(Point::new(4, 12), Size::new(40, 40));
        for dx in -1..=1 {
            for dy in -1..=1 {
                for solid in [false, true] {
                    let (mut ours, mut first) = (FrameBuffer::new(), FrameBuffer::new());
                    arrow(&mut ours, area, [dx, dy], solid).unwrap();
                    old_arrow(&mut first, area, [dx, dy], solid).unwrap();
                    assert!(ours.bytes() == first.bytes(), "{dx} {dy} {solid}");
                }
            }
        }
    }

    #[test]
    fn ascii_glyph_matches_the_fonts_mapping() {
        for font in [&BODY, &SMALL] {
            for c in (0..0x300)
                .filter_map(char::from_u32)
                .chain(['€', '中', '😀'])
            {
                let mut buf = [0; 4];
                let utf8 = c.encode_utf8(&mut buf).as_bytes();
                let lead = utf8[0];
                assert_eq!(
                    ascii_glyph(lead) as usize,
                    font.glyph_mapping.index(c),
                    "{c:?}"
                );
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
            line(&mut fb, a, b).unwrap();
            let on = fb.bytes().iter().map(|b| b.count_ones()).sum::<u32>();
            let major = (b.x - a.x).abs().max((b.y - a.y).abs()) as u32 + 1;
            assert_eq!(on, major, "{a:?} -> {b:?}");
            assert!(fb.pixel(a.x as usize, a.y as usize) && fb.pixel(b.x as usize, b.y as usize));
        }
    }
}
