//! Latin letters, digits and punctuation in single-stroke Hershey fonts, from
//! the hersheytext package (its JSON font data is public domain; licence and
//! acknowledgements in data/README.md). Embedded as data/hershey.txt.z.
//! Glyph coordinates there are font units with y down: cap top at 1,
//! baseline at 22, descenders to 29; the advance is twice the "o" value.

use crate::geom::{Pt, Stroke};
use std::collections::HashMap;
use std::sync::OnceLock;

static DATA: &[u8] = include_bytes!("../../data/hershey.txt.z");

/// The fonts the tool offers, with what they are.
pub const FONTS: &[(&str, &str)] = &[
    ("futural", "Hershey Sans 1-stroke (default)"),
    ("scripts", "Hershey Script 1-stroke"),
    ("cursive", "Hershey Script 1-stroke, alternate"),
    ("futuram", "Hershey Sans bold (double stroke)"),
];

/// One glyph in font units (y down).
pub struct Glyph {
    pub advance: f64,
    pub strokes: Vec<Vec<(f64, f64)>>,
}

type Font = Vec<Glyph>;

fn fonts() -> &'static HashMap<String, Font> {
    static F: OnceLock<HashMap<String, Font>> = OnceLock::new();
    F.get_or_init(|| {
        let raw = miniz_oxide::inflate::decompress_to_vec_zlib(DATA).expect("embedded font data");
        parse(std::str::from_utf8(&raw).expect("font data is UTF-8"))
    })
}

fn parse(text: &str) -> HashMap<String, Font> {
    let mut map: HashMap<String, Font> = HashMap::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        if let Some(name) = line.strip_prefix("font ") {
            current = Some(name.to_string());
            map.insert(name.to_string(), Vec::new());
            continue;
        }
        let (Some(font), Some((half, path))) = (&current, line.split_once(' ')) else {
            continue;
        };
        let half: f64 = half.parse().unwrap_or(8.0);
        map.get_mut(font).unwrap().push(Glyph {
            advance: 2.0 * half,
            strokes: parse_path(path),
        });
    }
    map
}

/// The font data's paths use only absolute M and L with "x,y" pairs.
fn parse_path(d: &str) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    for tok in d.split_whitespace() {
        let (new, xy) = match tok.as_bytes()[0] {
            b'M' => (true, &tok[1..]),
            b'L' => (false, &tok[1..]),
            _ => (false, tok),
        };
        let Some((x, y)) = xy.split_once(',') else {
            continue;
        };
        let (Ok(x), Ok(y)) = (x.parse::<f64>(), y.parse::<f64>()) else {
            continue;
        };
        if new || out.is_empty() {
            out.push(Vec::new());
        }
        out.last_mut().unwrap().push((x, y));
    }
    out.retain(|s| !s.is_empty());
    out
}

/// Whether `name` is an embedded font.
pub fn has_font(name: &str) -> bool {
    fonts().contains_key(name)
}

/// Font units from the baseline to the bottom of the character box.
pub const DESCENT: f64 = 7.0;
/// Font units per character box height.
pub const BOX: f64 = 32.0;
/// Advance of a space in font units.
pub const SPACE: f64 = 12.0;

/// Glyph for a printable ASCII character (33..=126), as strokes in units of
/// the character box (y up, 0 at the box bottom), and its advance in the
/// same units.
pub fn glyph(font: &str, ch: char) -> Option<(Vec<Stroke>, f64)> {
    let f = fonts().get(font)?;
    let code = ch as u32;
    if !(33..=126).contains(&code) {
        return None;
    }
    let g = f.get((code - 33) as usize)?;
    let baseline = 22.0;
    let strokes = g
        .strokes
        .iter()
        .map(|s| {
            s.iter()
                .map(|&(x, y)| Pt::new(x / BOX, (baseline + DESCENT - y) / BOX))
                .collect()
        })
        .collect();
    Some((strokes, g.advance / BOX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fonts_load_and_letters_have_strokes() {
        for (name, _) in FONTS {
            assert!(has_font(name), "{name}");
        }
        // 'B' in the sans font: three strokes, a vertical stem from cap top to baseline.
        let (b, adv) = glyph("futural", 'B').unwrap();
        assert_eq!(b.len(), 3);
        assert!((adv - 20.0 / BOX).abs() < 1e-12);
        let stem = &b[0];
        assert!((stem[0].y - 28.0 / BOX).abs() < 1e-12);
        assert!((stem[1].y - 7.0 / BOX).abs() < 1e-12);
        for c in ('0'..='9').chain('A'..='Z').chain('a'..='z') {
            assert!(
                glyph("futural", c).is_some_and(|(s, _)| !s.is_empty()),
                "{c}"
            );
        }
        assert!(glyph("futural", ' ').is_none());
        assert!(glyph("nope", 'A').is_none());
    }
}
