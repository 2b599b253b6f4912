//! Chinese characters as stroke medians, from the hanzi-writer-data package
//! (derived from Make Me a Hanzi / Arphic fonts; licence in data/README.md).
//! The data ships inside the binary (data/hanzi_medians.bin.z, zlib, built by
//! data/build_data.py) and is decoded once on first use, so the tool needs no
//! network and no files at run time.

use crate::geom::{Pt, Stroke};
use std::collections::HashMap;
use std::sync::OnceLock;

static DATA: &[u8] = include_bytes!("../../data/hanzi_medians.bin.z");

type Medians = Vec<Vec<(i16, i16)>>;

fn table() -> &'static HashMap<char, Medians> {
    static T: OnceLock<HashMap<char, Medians>> = OnceLock::new();
    T.get_or_init(|| decode(DATA).expect("embedded hanzi data is valid"))
}

fn decode(z: &[u8]) -> Option<HashMap<char, Medians>> {
    let raw = miniz_oxide::inflate::decompress_to_vec_zlib(z).ok()?;
    let mut r = Reader { b: &raw, at: 0 };
    if r.take(4)? != b"IKHZ" {
        return None;
    }
    let n = r.u32()?;
    let mut map = HashMap::with_capacity(n as usize);
    for _ in 0..n {
        let ch = char::from_u32(r.u32()?)?;
        let strokes = r.u8()?;
        let mut med = Vec::with_capacity(strokes as usize);
        for _ in 0..strokes {
            let pts = r.u8()?;
            let mut s = Vec::with_capacity(pts as usize);
            for _ in 0..pts {
                s.push((r.i16()?, r.i16()?));
            }
            med.push(s);
        }
        map.insert(ch, med);
    }
    Some(map)
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.b.get(self.at..self.at + n)?;
        self.at += n;
        Some(s)
    }
    fn u8(&mut self) -> Option<u8> {
        Some(self.take(1)?[0])
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn i16(&mut self) -> Option<i16> {
        Some(i16::from_le_bytes(self.take(2)?.try_into().ok()?))
    }
}

/// Number of characters in the embedded set.
pub fn count() -> usize {
    table().len()
}

/// The strokes of `ch` in writing order, in a unit box (0..1 both ways, y up,
/// the data's baseline offset of 124/1024 kept), or None if not in the set.
pub fn glyph(ch: char) -> Option<Vec<Stroke>> {
    table().get(&ch).map(|med| {
        med.iter()
            .map(|s| {
                s.iter()
                    .map(|&(x, y)| Pt::new(x as f64 / 1024.0, (y as f64 + 124.0) / 1024.0))
                    .collect()
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_covers_common_characters() {
        assert!(count() > 9000, "{}", count());
        // 风 has four strokes; its first median starts at (244, 673).
        let g = glyph('风').unwrap();
        assert_eq!(g.len(), 4);
        assert!((g[0][0].x - 244.0 / 1024.0).abs() < 1e-12);
        assert!((g[0][0].y - (673.0 + 124.0) / 1024.0).abs() < 1e-12);
        for c in "一帆风顺中国地质大学写字机器人".chars() {
            let g = glyph(c).unwrap();
            assert!(!g.is_empty());
            assert!(g
                .iter()
                .flatten()
                .all(|p| (-0.1..1.1).contains(&p.x) && (-0.1..1.1).contains(&p.y)));
        }
        assert!(glyph('A').is_none());
    }
}
