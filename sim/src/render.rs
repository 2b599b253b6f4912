//! The finished drawing, rendered from a step trace as PNG and SVG.
//!
//! Owns only the picture: which rows are pen-down strokes and how they are scaled. The
//! pen is down while Z is nearer the pen-down than the pen-up height of the settings
//! ($206 / $205); a program that never moves Z (a servo pen, or a path test such as the
//! bench programs) counts as drawn throughout.

use crate::trace::Trace;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// Pen-down polylines in mm, and pen-up travel moves, from a trace that starts at `start`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Drawing {
    pub strokes: Vec<Vec<[f64; 2]>>,
    pub travel: Vec<[[f64; 2]; 2]>,
}

/// Pen heights in Z steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pen {
    pub up: i32,
    pub down: i32,
}

impl Pen {
    /// The Z-axis pen heights of the settings, in steps.
    pub fn from_settings(s: &inkstep_core::settings::Settings) -> Pen {
        let spmm = s.steps_per_mm(2);
        Pen {
            up: (s.pen_z_up() * spmm).round() as i32,
            down: (s.pen_z_down() * spmm).round() as i32,
        }
    }

    fn is_down(self, z: i32) -> bool {
        (i64::from(z) - i64::from(self.down)).abs() < (i64::from(z) - i64::from(self.up)).abs()
    }
}

impl Drawing {
    pub fn from_trace(trace: &Trace, start: [i32; 3], steps_per_mm: [f64; 2], pen: Pen) -> Drawing {
        let mm = |p: [i32; 3]| [p[0] as f64 / steps_per_mm[0], p[1] as f64 / steps_per_mm[1]];
        let z_moves = trace.rows.iter().any(|r| r.pos[2] != start[2]);
        let down_at = |z: i32| !z_moves || pen.is_down(z);
        let mut d = Drawing::default();
        let mut prev = start;
        let mut current: Vec<[f64; 2]> = Vec::new();
        let mut up_from: Option<[f64; 2]> = None;
        for row in &trace.rows {
            let down = down_at(prev[2]) && down_at(row.pos[2]);
            let xy_moved = row.pos[0] != prev[0] || row.pos[1] != prev[1];
            if down {
                if let Some(from) = up_from.take() {
                    if from != mm(prev) {
                        d.travel.push([from, mm(prev)]);
                    }
                }
                if current.is_empty() {
                    current.push(mm(prev));
                }
                if xy_moved {
                    current.push(mm(row.pos));
                }
            } else {
                if current.len() > 1 {
                    d.strokes.push(std::mem::take(&mut current));
                }
                current.clear();
                if up_from.is_none() {
                    up_from = Some(mm(prev));
                }
            }
            prev = row.pos;
        }
        if current.len() > 1 {
            d.strokes.push(current);
        }
        d
    }

    /// Bounding box of the strokes: (min, max), or a unit box when nothing was drawn.
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let pts = self
            .strokes
            .iter()
            .flatten()
            .chain(self.travel.iter().flatten());
        for p in pts {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if lo[0] > hi[0] {
            return ([0.0, 0.0], [1.0, 1.0]);
        }
        (lo, hi)
    }

    /// SVG in millimetres (Y up, as on the machine); travel dashed in grey.
    pub fn to_svg(&self) -> String {
        let (lo, hi) = self.bounds();
        let m = 2.0;
        let (w, h) = (
            (hi[0] - lo[0]).max(1.0) + 2.0 * m,
            (hi[1] - lo[1]).max(1.0) + 2.0 * m,
        );
        let mut s = String::new();
        writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.3}mm" height="{h:.3}mm" viewBox="{:.4} {:.4} {w:.4} {h:.4}">"#,
            lo[0] - m,
            -hi[1] - m
        )
        .unwrap();
        writeln!(
            s,
            r##"<rect x="{:.4}" y="{:.4}" width="{w:.4}" height="{h:.4}" fill="white"/>"##,
            lo[0] - m,
            -hi[1] - m
        )
        .unwrap();
        for t in &self.travel {
            writeln!(
                s,
                r##"<line x1="{:.4}" y1="{:.4}" x2="{:.4}" y2="{:.4}" stroke="#bbbbbb" stroke-width="0.15" stroke-dasharray="0.8 0.8"/>"##,
                t[0][0], -t[0][1], t[1][0], -t[1][1]
            )
            .unwrap();
        }
        for stroke in &self.strokes {
            s.push_str(r##"<polyline fill="none" stroke="#1a3a8a" stroke-width="0.3" stroke-linejoin="round" stroke-linecap="round" points=""##);
            for p in stroke {
                write!(s, "{:.4},{:.4} ", p[0], -p[1]).unwrap();
            }
            s.push_str("\"/>\n");
        }
        s.push_str("</svg>\n");
        s
    }

    /// PNG of about `size` pixels on the longer side, white paper, blue ink.
    pub fn write_png(&self, path: &Path, size: u32) -> Result<(), String> {
        let (lo, hi) = self.bounds();
        let (w_mm, h_mm) = ((hi[0] - lo[0]).max(1.0), (hi[1] - lo[1]).max(1.0));
        let margin = 20.0;
        let scale = (size as f64 - 2.0 * margin) / w_mm.max(h_mm);
        let (w, h) = (
            (w_mm * scale + 2.0 * margin) as u32,
            (h_mm * scale + 2.0 * margin) as u32,
        );
        let px = |p: &[f64; 2]| {
            (
                ((p[0] - lo[0]) * scale + margin) as i32,
                ((hi[1] - p[1]) * scale + margin) as i32,
            )
        };
        let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
        let err = |e: DrawingAreaErrorKind<_>| format!("{}: {e:?}", path.display());
        root.fill(&WHITE).map_err(err)?;
        let grey = RGBColor(190, 190, 190);
        for t in &self.travel {
            root.draw(&PathElement::new(
                vec![px(&t[0]), px(&t[1])],
                grey.stroke_width(1),
            ))
            .map_err(err)?;
        }
        let ink = RGBColor(26, 58, 138);
        for stroke in &self.strokes {
            let pts: Vec<(i32, i32)> = stroke.iter().map(px).collect();
            root.draw(&PathElement::new(pts, ink.stroke_width(2)))
                .map_err(err)?;
        }
        root.present().map_err(err)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::Row;

    fn tr(pos: &[[i32; 3]]) -> Trace {
        Trace {
            rows: pos
                .iter()
                .enumerate()
                .map(|(i, &pos)| Row {
                    t_us: i as f64,
                    pos,
                })
                .collect(),
        }
    }

    const PEN: Pen = Pen { up: 1, down: 0 };

    #[test]
    fn without_z_motion_everything_is_drawn() {
        let t = tr(&[[1, 0, 5], [2, 1, 5]]);
        let d = Drawing::from_trace(&t, [0, 0, 5], [1.0, 1.0], PEN);
        assert_eq!(d.strokes, vec![vec![[0.0, 0.0], [1.0, 0.0], [2.0, 1.0]]]);
    }

    #[test]
    fn pen_up_splits_strokes_and_records_travel() {
        let t = tr(&[
            [1, 0, 0],
            [2, 0, 0],
            [2, 0, 1],
            [5, 5, 1],
            [5, 5, 0],
            [6, 5, 0],
        ]);
        let d = Drawing::from_trace(&t, [0, 0, 0], [1.0, 1.0], PEN);
        assert_eq!(
            d.strokes,
            vec![
                vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
                vec![[5.0, 5.0], [6.0, 5.0]]
            ]
        );
        assert_eq!(d.travel, vec![[[2.0, 0.0], [5.0, 5.0]]]);
        assert_eq!(d.bounds(), ([0.0, 0.0], [6.0, 5.0]));
        // Travel does not widen the picture.
        let far = tr(&[
            [1, 0, 0],
            [1, 0, 1],
            [50, 50, 1],
            [1, 0, 1],
            [1, 0, 0],
            [2, 0, 0],
        ]);
        assert_eq!(
            Drawing::from_trace(&far, [0, 0, 0], [1.0, 1.0], PEN).bounds(),
            ([0.0, 0.0], [2.0, 0.0])
        );
        let svg = d.to_svg();
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<line").count(), 1);
        assert!(svg.contains("6.0000,-5.0000"));
    }

    #[test]
    fn png_is_written() {
        let t = tr(&[[80, 0, 0], [80, 80, 0], [0, 0, 0]]);
        let d = Drawing::from_trace(&t, [0, 0, 0], [80.0, 80.0], PEN);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("d.png");
        d.write_png(&p, 200).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
    }
}
