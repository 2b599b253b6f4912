//! The simulated ST7920 128x64 LCD: turns the core's frame into a scaled PNG in
//! ST7920-like colours (light pixels on a blue backlight).
//!
//! Owns only the conversion to an image; what is on the screen is drawn by the core's
//! screens into the core's frame buffer, exactly as on the board.

use embedded_graphics::pixelcolor::BinaryColor;
use embedded_graphics::prelude::*;
use embedded_graphics_simulator::{BinaryColorTheme, OutputSettingsBuilder, SimulatorDisplay};
use std::path::Path;

pub const WIDTH: u32 = 128;
pub const HEIGHT: u32 = 64;
/// Pixel scale of the PNGs (128x64 -> 512x256 plus spacing).
pub const SCALE: u32 = 4;

/// Writes a 128x64 frame, given as "pixel (x, y) is on", as a PNG.
pub fn save_png(pixel: impl Fn(usize, usize) -> bool, path: &Path) -> Result<(), String> {
    let mut display = SimulatorDisplay::<BinaryColor>::new(Size::new(WIDTH, HEIGHT));
    let on = (0..HEIGHT as usize)
        .flat_map(|y| (0..WIDTH as usize).map(move |x| (x, y)))
        .filter(|&(x, y)| pixel(x, y))
        .map(|(x, y)| Pixel(Point::new(x as i32, y as i32), BinaryColor::On));
    display.draw_iter(on).map_err(|e| format!("{e:?}"))?;
    let settings = OutputSettingsBuilder::new()
        .theme(BinaryColorTheme::LcdBlue)
        .scale(SCALE)
        .pixel_spacing(1)
        .build();
    display
        .to_rgb_output_image(&settings)
        .save_png(path)
        .map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_a_scaled_png_with_lit_pixels() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("lcd.png");
        save_png(|x, y| x == y, &p).unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&p).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        // 128 pixels of 4 plus 127 gaps of 1 (and a border of spacing on each side).
        assert!(info.width >= WIDTH * SCALE && info.width <= WIDTH * (SCALE + 1) + 1);
        let px = |x: u32, y: u32| {
            let i = ((y * info.width + x) * 3) as usize;
            [buf[i], buf[i + 1], buf[i + 2]]
        };
        // Pixel (0, 0) is lit, pixel (1, 0) is not: they differ in colour.
        let step = SCALE + 1;
        assert_ne!(px(2, 2), px(step + 2, 2));
    }
}
