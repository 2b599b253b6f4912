//! The 128x64 1-bit frame buffer that the screens draw into, with dirty tracking.
//!
//! The ST7920 is written through a slow serial link (see [`super::st7920`]), so the
//! firmware must send only what changed. Each pixel write compares with the stored
//! value and marks its 16-pixel word dirty only on a real change; the screens paint in
//! place (text with its background, fixed-width fields) instead of clearing and
//! redrawing, so unchanged pixels cost nothing. 1 KB of pixels + 64 bytes of dirty
//! bits: no second "shadow" buffer is needed.

use core::convert::Infallible;

use embedded_graphics::pixelcolor::BinaryColor;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::Rectangle;

pub const WIDTH: usize = 128;
pub const HEIGHT: usize = 64;
/// Bytes per pixel row (8 pixels a byte, MSB leftmost, as the ST7920 GDRAM).
pub const ROW_BYTES: usize = WIDTH / 8;
/// 16-pixel words per row (the ST7920 horizontal address unit).
pub const ROW_WORDS: usize = WIDTH / 16;

/// A 128x64 monochrome frame buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameBuffer {
    buf: [u8; ROW_BYTES * HEIGHT],
    /// Bit w of `dirty[y]`: word w of row y changed since the last flush.
    dirty: [u8; HEIGHT],
}

impl Default for FrameBuffer {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameBuffer {
    /// A blank buffer, entirely dirty: what the LCD shows at power-up is unknown.
    pub const fn new() -> Self {
        FrameBuffer {
            buf: [0; ROW_BYTES * HEIGHT],
            dirty: [0xff; HEIGHT],
        }
    }

    /// Pixel at (x, y); false outside the screen.
    pub fn pixel(&self, x: usize, y: usize) -> bool {
        if x >= WIDTH || y >= HEIGHT {
            return false;
        }
        self.buf
            .get(y * ROW_BYTES + x / 8)
            .is_some_and(|b| b & (0x80 >> (x % 8)) != 0)
    }

    /// Set one pixel; off-screen coordinates are ignored.
    pub fn set(&mut self, x: i32, y: i32, on: bool) {
        if x < 0 || y < 0 || x >= WIDTH as i32 || y >= HEIGHT as i32 {
            return;
        }
        let (x, y) = (x as usize, y as usize);
        let mask = 0x80u8 >> (x % 8);
        let Some(byte) = self.buf.get_mut(y * ROW_BYTES + x / 8) else {
            return;
        };
        let new = if on { *byte | mask } else { *byte & !mask };
        if new != *byte {
            *byte = new;
            if let Some(d) = self.dirty.get_mut(y) {
                *d |= 1 << (x / 16);
            }
        }
    }

    /// Paint `n` (at most 32) pixels of row `y` from `x` on: pixel `x + i` is bit
    /// `31 - i` of `bits` (left-aligned, leftmost pixel in the MSB), clipped to the
    /// screen. The same pixels and dirty words as `n` calls of [`Self::set`], a byte
    /// at a time: text and fills paint whole glyph rows and spans this way.
    pub fn set_bits(&mut self, x: i32, y: i32, bits: u32, n: u32) {
        if y < 0 || y >= HEIGHT as i32 || n == 0 {
            return;
        }
        let (mut x, mut bits, mut n) = (x, bits, n.min(32));
        if x < 0 {
            let skip = x.unsigned_abs();
            if skip >= n {
                return;
            }
            bits <<= skip;
            n -= skip;
            x = 0;
        }
        if x >= WIDTH as i32 {
            return;
        }
        let x = x as u32;
        n = n.min(WIDTH as u32 - x);
        // 32-bit arithmetic only (the Cortex-M3 shifts 64 bits in a library call): a
        // run that does not fit the four bytes from x's goes in two.
        if x % 8 + n > 32 {
            self.paint(x, y as usize, bits, 24);
            self.paint(x + 24, y as usize, bits << 24, n - 24);
        } else {
            self.paint(x, y as usize, bits, n);
        }
    }

    /// [`Self::set_bits`] on screen, with `x % 8 + n <= 32` and `x + n <= WIDTH`.
    fn paint(&mut self, x: u32, y: usize, bits: u32, n: u32) {
        let mask = !(u32::MAX >> n);
        let sh = x % 8;
        let v = (bits & mask) >> sh;
        let m = mask >> sh;
        let first = x as usize / 8;
        let last = (x + n - 1) as usize / 8;
        let row = y * ROW_BYTES;
        let mut changed = 0u8;
        for bx in first..=last {
            let shift = 24 - 8 * (bx - first) as u32;
            let (mk, vk) = ((m >> shift) as u8, (v >> shift) as u8);
            let Some(byte) = self.buf.get_mut(row + bx) else {
                return;
            };
            let new = (*byte & !mk) | vk;
            if new != *byte {
                *byte = new;
                changed |= 1 << (bx / 2);
            }
        }
        if let Some(d) = self.dirty.get_mut(y) {
            *d |= changed;
        }
    }

    /// Fill the `w` x `h` rectangle at (x, y), clipped to the screen.
    pub fn fill(&mut self, x: i32, y: i32, w: i32, h: i32, on: bool) {
        let x0 = x.max(0);
        let x1 = x.saturating_add(w).min(WIDTH as i32);
        let y1 = y.saturating_add(h).min(HEIGHT as i32);
        let bits = if on { u32::MAX } else { 0 };
        for yy in y.max(0)..y1 {
            let mut xx = x0;
            while xx < x1 {
                let n = (x1 - xx).min(24);
                self.set_bits(xx, yy, bits, n as u32);
                xx += n;
            }
        }
    }

    /// The 16 bytes of pixel row `y` (empty if out of range).
    pub fn row(&self, y: usize) -> &[u8] {
        self.buf
            .get(y * ROW_BYTES..(y + 1) * ROW_BYTES)
            .unwrap_or(&[])
    }

    /// Dirty-word mask of row `y` (bit w = pixels 16w..16w+15).
    pub fn dirty_words(&self, y: usize) -> u8 {
        self.dirty.get(y).copied().unwrap_or(0)
    }

    /// Anything to send?
    pub fn is_dirty(&self) -> bool {
        self.dirty.iter().any(|d| *d != 0)
    }

    /// Number of dirty 16-pixel words.
    pub fn dirty_word_count(&self) -> u32 {
        self.dirty.iter().map(|d| d.count_ones()).sum()
    }

    /// Force a full resend (e.g. after the LCD was reset).
    pub fn mark_all_dirty(&mut self) {
        self.dirty = [0xff; HEIGHT];
    }

    /// Everything has been sent.
    pub fn mark_clean(&mut self) {
        self.dirty = [0; HEIGHT];
    }

    /// The raw pixels, row-major, MSB leftmost.
    pub fn bytes(&self) -> &[u8; ROW_BYTES * HEIGHT] {
        &self.buf
    }
}

impl FrameBuffer {
    /// Draw this frame onto any embedded-graphics target (the simulator's display,
    /// another panel's driver): the screens paint into a `FrameBuffer` (which keeps the
    /// firmware free of generic drawing code and tracks what changed), and this hands
    /// the result to whatever `DrawTarget` shows it, every pixel on or off.
    pub fn draw_onto<D: DrawTarget<Color = BinaryColor>>(
        &self,
        target: &mut D,
    ) -> Result<(), D::Error> {
        let pixels = (0..HEIGHT)
            .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
            .map(|(x, y)| {
                Pixel(
                    Point::new(x as i32, y as i32),
                    BinaryColor::from(self.pixel(x, y)),
                )
            });
        target.draw_iter(pixels)
    }
}

impl OriginDimensions for FrameBuffer {
    fn size(&self) -> Size {
        Size::new(WIDTH as u32, HEIGHT as u32)
    }
}

impl DrawTarget for FrameBuffer {
    type Color = BinaryColor;
    type Error = Infallible;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Pixel<Self::Color>>,
    {
        for Pixel(p, c) in pixels {
            self.set(p.x, p.y, c.is_on());
        }
        Ok(())
    }

    fn fill_solid(&mut self, area: &Rectangle, color: Self::Color) -> Result<(), Self::Error> {
        let len = |l: u32| l.min(1 << 16) as i32;
        let (p, s) = (area.top_left, area.size);
        self.fill(p.x, p.y, len(s.width), len(s.height), color.is_on());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_graphics::primitives::{PrimitiveStyle, Rectangle};

    #[test]
    fn only_real_changes_mark_words_dirty() {
        let mut fb = FrameBuffer::new();
        assert_eq!(fb.dirty_word_count(), 512);
        fb.mark_clean();
        fb.set(17, 3, false); // already off
        assert!(!fb.is_dirty());
        fb.set(17, 3, true);
        assert_eq!(fb.dirty_words(3), 0b10);
        assert!(fb.pixel(17, 3));
        assert_eq!(fb.row(3)[2], 0x40);
        fb.mark_clean();
        fb.set(17, 3, true); // same value again
        fb.set(-1, 3, true);
        fb.set(0, 64, true);
        assert!(!fb.is_dirty());
    }

    /// Row painting (glyph rows, fills) gives the pixels and dirty words that pixel
    /// by pixel painting gives, on a busy picture, clipped at every edge.
    #[test]
    fn painting_a_row_at_once_equals_pixel_by_pixel() {
        let mut seed = 0x1234_5678u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            seed
        };
        let mut start = FrameBuffer::new();
        for y in 0..HEIGHT as i32 {
            for x in 0..WIDTH as i32 {
                start.set(x, y, next() & 1 != 0);
            }
        }
        start.mark_clean();
        for _ in 0..2000 {
            let (x, y) = ((next() % 180) as i32 - 30, (next() % 80) as i32 - 8);
            let (bits, n) = (next(), next() % 34);
            let mut ours = start.clone();
            let mut theirs = start.clone();
            ours.set_bits(x, y, bits, n);
            for i in 0..n.min(32) {
                theirs.set(x + i as i32, y, bits & (1 << (31 - i)) != 0);
            }
            assert_eq!(ours, theirs, "set_bits({x}, {y}, {bits:#x}, {n})");
            let (w, h, on) = (
                (next() % 150) as i32 - 5,
                (next() % 12) as i32,
                bits & 1 != 0,
            );
            let mut ours = start.clone();
            let mut theirs = start.clone();
            ours.fill(x, y, w, h, on);
            for yy in y..y + h {
                for xx in x..x + w {
                    theirs.set(xx, yy, on);
                }
            }
            assert_eq!(ours, theirs, "fill({x}, {y}, {w}, {h}, {on})");
        }
    }

    #[test]
    fn a_frame_draws_onto_any_draw_target() {
        let mut fb = FrameBuffer::new();
        fb.fill(3, 5, 20, 7, true);
        fb.set(127, 63, true);
        // Another DrawTarget, here a second frame buffer with different content.
        let mut other = FrameBuffer::new();
        other.fill(0, 0, 128, 64, true);
        fb.draw_onto(&mut other).unwrap();
        assert_eq!(other.bytes(), fb.bytes());
    }

    #[test]
    fn repainting_identical_content_leaves_it_clean() {
        let mut fb = FrameBuffer::new();
        let r = Rectangle::new(Point::new(10, 10), Size::new(40, 20));
        r.into_styled(PrimitiveStyle::with_fill(BinaryColor::On))
            .draw(&mut fb)
            .unwrap();
        fb.mark_clean();
        r.into_styled(PrimitiveStyle::with_fill(BinaryColor::On))
            .draw(&mut fb)
            .unwrap();
        assert!(!fb.is_dirty());
        // A fill that runs off the screen is clipped, not a panic.
        Rectangle::new(Point::new(120, 60), Size::new(40, 40))
            .into_styled(PrimitiveStyle::with_fill(BinaryColor::On))
            .draw(&mut fb)
            .unwrap();
        assert_eq!(fb.dirty_words(63), 0x80);
    }
}
