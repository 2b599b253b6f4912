//! Text layout: characters left to right in boxes of `size` (mm), Chinese
//! from stroke medians (one full box each), everything else printable from a
//! Hershey font (proportional advance). Lines break at '\n' and stack
//! downwards; the last line's box bottom sits on y = 0 so the drawing lies
//! in the positive quadrant, where plotters home. Strokes keep writing order
//! (the "natural" order the planner is measured against).

use crate::font::{hanzi, hershey};
use crate::geom::{Pt, Stroke};
use anyhow::{bail, Result};

/// Line pitch as a multiple of the character box.
pub const LINE_PITCH: f64 = 1.25;

#[derive(Clone, Debug)]
pub struct Layout {
    pub strokes: Vec<Stroke>,
    /// Index of the first stroke of every drawn character.
    pub char_starts: Vec<usize>,
    pub width: f64,
    pub height: f64,
}

/// Lays out `text` with a character box of `size` mm and a Hershey `font`.
pub fn layout(text: &str, size: f64, font: &str) -> Result<Layout> {
    if !hershey::has_font(font) {
        let names: Vec<_> = hershey::FONTS.iter().map(|f| f.0).collect();
        bail!("unknown font {font:?}; fonts: {}", names.join(", "));
    }
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Layout {
        strokes: Vec::new(),
        char_starts: Vec::new(),
        width: 0.0,
        height: 0.0,
    };
    let mut missing = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let y0 = (lines.len() - 1 - k) as f64 * LINE_PITCH * size;
        let mut x = 0.0;
        for ch in line.chars() {
            let (glyph, advance) = if ch == ' ' {
                (Vec::new(), hershey::SPACE / hershey::BOX)
            } else if ch == '\u{3000}' {
                (Vec::new(), 1.0)
            } else if let Some(g) = hanzi::glyph(ch) {
                (g, 1.0)
            } else if let Some(g) = hershey::glyph(font, ch) {
                g
            } else if let Some(g) = cjk_punctuation(ch, font) {
                (g, 1.0)
            } else {
                missing.push(ch);
                continue;
            };
            if !glyph.is_empty() {
                out.char_starts.push(out.strokes.len());
            }
            out.strokes.extend(glyph.into_iter().map(|s| {
                s.into_iter()
                    .map(|p| Pt::new(x + p.x * size, y0 + p.y * size))
                    .collect::<Stroke>()
            }));
            x += advance * size;
        }
        out.width = out.width.max(x);
    }
    if !missing.is_empty() {
        bail!("no stroke data for: {}", missing.iter().collect::<String>());
    }
    out.height = if lines.is_empty() {
        0.0
    } else {
        ((lines.len() - 1) as f64 * LINE_PITCH + 1.0) * size
    };
    Ok(out)
}

/// Chinese punctuation, which the medians do not cover, in a full box:
/// full-width ASCII forms and quotes from the Hershey font, the ideographic
/// full stop as a small circle.
fn cjk_punctuation(ch: char, font: &str) -> Option<Vec<Stroke>> {
    let ascii = match ch {
        '\u{FF01}'..='\u{FF5E}' => char::from_u32(ch as u32 - 0xFEE0)?,
        '\u{3001}' => ',',
        '\u{201C}' | '\u{201D}' => '"',
        '\u{2018}' | '\u{2019}' => '\'',
        '\u{3002}' => {
            let circle = (0..=16)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 16.0;
                    Pt::new(0.2 + 0.07 * a.cos(), 0.2 + 0.07 * a.sin())
                })
                .collect();
            return Some(vec![circle]);
        }
        _ => return None,
    };
    hershey::glyph(font, ascii).map(|(g, _)| g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::bounds;

    #[test]
    fn mixed_scripts_go_left_to_right_in_their_boxes() {
        let l = layout("一帆 Hi", 10.0, "futural").unwrap();
        // 一 (1 stroke) + 帆 (6) + H (3) + i (2)
        assert_eq!(l.char_starts.len(), 4);
        assert_eq!(l.strokes.len(), 1 + 6 + 3 + 2);
        let first = bounds(&l.strokes[..1]).unwrap();
        assert!(first.0.x >= 0.0 && first.1.x <= 10.0);
        let fan = bounds(&l.strokes[1..7]).unwrap();
        assert!(fan.0.x >= 10.0 && fan.1.x <= 20.0);
        let h = bounds(&l.strokes[7..10]).unwrap();
        assert!(h.0.x >= 20.0 + 10.0 * 12.0 / 32.0 - 1e-9, "{h:?}");
        // Capital H: cap height 21/32 of the box, baseline 7/32 above the box bottom.
        assert!((h.1.y - h.0.y - 21.0 / 32.0 * 10.0).abs() < 1e-9);
        assert!((h.0.y - 7.0 / 32.0 * 10.0).abs() < 1e-9);
        for p in l.strokes.iter().flatten() {
            assert!(p.y >= -1.0 && p.y <= 11.0);
        }
        assert!(l.width > 30.0 && l.width < 45.0);
    }

    #[test]
    fn lines_stack_down_and_unknown_characters_are_reported() {
        let l = layout("A\nB", 10.0, "futural").unwrap();
        let a = bounds(&l.strokes[..l.char_starts[1]]).unwrap();
        let b = bounds(&l.strokes[l.char_starts[1]..]).unwrap();
        assert!(a.0.y > b.1.y);
        assert!((l.height - 22.5).abs() < 1e-9);
        // Chinese punctuation takes a full box.
        let p = layout("你好，世界！。", 10.0, "futural").unwrap();
        assert_eq!(p.char_starts.len(), 7);
        assert!((p.width - 70.0).abs() < 1e-9);
        let err = layout("A\u{1F600}", 10.0, "futural").unwrap_err();
        assert!(err.to_string().contains('\u{1F600}'));
        assert!(layout("A", 10.0, "nope").is_err());
    }
}
