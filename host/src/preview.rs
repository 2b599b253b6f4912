//! G-code preview as PNG: pen-down strokes in dark blue, pen-up travel in
//! thin dashed red, the start as a green dot, fitted into the image with a
//! margin and y up like the machine. tiny-skia does the anti-aliased drawing.
//! For an SVG, [`Extra`] adds what the G-code cannot show: the page outline
//! (grey), the machine travel (dashed grey) and what was left out (text,
//! images, fills not hatched: orange, shaded), so the picture tells the truth
//! about the file, not only about the program.

use crate::geom::Pt;
use crate::toolpath::{Move, MoveKind};
use anyhow::{anyhow, Result};
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Stroke, StrokeDash, Transform};

pub struct Stats {
    pub draw_mm: f64,
    pub travel_mm: f64,
}

/// What else to draw around the moves.
#[derive(Clone, Debug, Default)]
pub struct Extra {
    /// Outlines (mm) of what the program leaves out: each item closed rings,
    /// inside by even-odd.
    pub left_out: Vec<Vec<Vec<Pt>>>,
    /// Page size (mm), its corner at the origin.
    pub page: Option<(f64, f64)>,
    /// Machine travel (mm), from the origin.
    pub travel: Option<(f64, f64)>,
}

/// Colour of what is left out.
pub const LEFT_OUT_RGB: (u8, u8, u8) = (240, 140, 0);

/// Renders the moves into a PNG of `width` pixels (height follows the aspect).
pub fn render(moves: &[Move], width: u32) -> Result<(Pixmap, Stats)> {
    render_with(moves, &Extra::default(), width)
}

fn rect(w: f64, h: f64) -> Vec<Pt> {
    vec![
        Pt::new(0.0, 0.0),
        Pt::new(w, 0.0),
        Pt::new(w, h),
        Pt::new(0.0, h),
        Pt::new(0.0, 0.0),
    ]
}

/// [`render`] with the page, the travel and what was left out.
pub fn render_with(moves: &[Move], extra: &Extra, width: u32) -> Result<(Pixmap, Stats)> {
    let page = extra.page.map(|(w, h)| rect(w, h));
    let travel = extra.travel.map(|(w, h)| rect(w, h));
    let pts = moves
        .iter()
        .flat_map(|m| [m.from, m.to])
        .chain(extra.left_out.iter().flatten().flatten().copied())
        .chain(page.iter().flatten().copied())
        .chain(travel.iter().flatten().copied())
        .filter(|p| p.x.is_finite() && p.y.is_finite());
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    let mut any = false;
    for p in pts {
        any = true;
        lo = (lo.0.min(p.x), lo.1.min(p.y));
        hi = (hi.0.max(p.x), hi.1.max(p.y));
    }
    if !any {
        lo = (0.0, 0.0);
        hi = (1.0, 1.0);
    }
    let (w_mm, h_mm) = ((hi.0 - lo.0).max(1e-3), (hi.1 - lo.1).max(1e-3));
    let margin = 20.0;
    let scale = (width as f64 - 2.0 * margin) / w_mm;
    let height = ((h_mm * scale + 2.0 * margin).ceil() as u32).clamp(1, 16384);
    let mut pm = Pixmap::new(width, height).ok_or_else(|| anyhow!("bad image size"))?;
    pm.fill(Color::WHITE);
    let to_px = |x: f64, y: f64| {
        (
            (margin + (x - lo.0) * scale) as f32,
            (height as f64 - margin - (y - lo.1) * scale) as f32,
        )
    };
    let line_w = (width as f32 / 600.0).max(1.0);
    let rings = |rings: &[Vec<Pt>]| {
        let mut pb = PathBuilder::new();
        for pts in rings {
            for (k, p) in pts.iter().enumerate() {
                let (x, y) = to_px(p.x, p.y);
                if k == 0 {
                    pb.move_to(x, y);
                } else {
                    pb.line_to(x, y);
                }
            }
        }
        pb.finish()
    };
    for (r, dashed) in [(&page, false), (&travel, true)] {
        if let Some(path) = r.as_ref().and_then(|r| rings(std::slice::from_ref(r))) {
            let mut paint = Paint::default();
            paint.set_color_rgba8(150, 150, 150, 255);
            let stroke = Stroke {
                width: line_w,
                dash: dashed
                    .then(|| StrokeDash::new(vec![8.0 * line_w, 4.0 * line_w], 0.0))
                    .flatten(),
                ..Stroke::default()
            };
            pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
    for o in &extra.left_out {
        if let Some(path) = rings(o) {
            let (r, g, b) = LEFT_OUT_RGB;
            let mut paint = Paint::default();
            paint.set_color_rgba8(r, g, b, 70);
            pm.fill_path(
                &path,
                &paint,
                FillRule::EvenOdd,
                Transform::identity(),
                None,
            );
            paint.set_color_rgba8(r, g, b, 255);
            let stroke = Stroke {
                width: line_w * 1.5,
                ..Stroke::default()
            };
            pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
    let mut stats = Stats {
        draw_mm: 0.0,
        travel_mm: 0.0,
    };
    let mut draw = PathBuilder::new();
    let mut travel_pb = PathBuilder::new();
    // Where each builder's current polyline ends: a move that starts there
    // continues it (one subpath per stroke, not per move, which keeps a
    // program of millions of moves quick to stroke).
    let (mut draw_at, mut travel_at) = (None, None);
    for m in moves {
        let (pb, acc, at) = match m.kind {
            MoveKind::Draw => (&mut draw, &mut stats.draw_mm, &mut draw_at),
            MoveKind::Travel => (&mut travel_pb, &mut stats.travel_mm, &mut travel_at),
        };
        *acc += m.from.dist(m.to);
        let a = to_px(m.from.x, m.from.y);
        let b = to_px(m.to.x, m.to.y);
        if *at != Some(a) {
            pb.move_to(a.0, a.1);
        }
        pb.line_to(b.0, b.1);
        *at = Some(b);
    }
    if let Some(path) = travel_pb.finish() {
        let mut paint = Paint::default();
        paint.set_color_rgba8(220, 60, 60, 200);
        paint.anti_alias = true;
        let stroke = Stroke {
            width: line_w,
            dash: StrokeDash::new(vec![4.0 * line_w, 3.0 * line_w], 0.0),
            ..Stroke::default()
        };
        pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    if let Some(path) = draw.finish() {
        let mut paint = Paint::default();
        paint.set_color_rgba8(20, 40, 120, 255);
        paint.anti_alias = true;
        let stroke = Stroke {
            width: line_w * 2.0,
            line_cap: tiny_skia::LineCap::Round,
            line_join: tiny_skia::LineJoin::Round,
            ..Stroke::default()
        };
        pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    // Drawn parts outside the machine travel, over the blue in orange.
    if let Some((tw, th)) = extra.travel {
        let mut out_pb = PathBuilder::new();
        for m in moves.iter().filter(|m| m.kind == MoveKind::Draw) {
            for (a, b) in outside_pieces(m.from, m.to, tw, th) {
                let (p, q) = (to_px(a.x, a.y), to_px(b.x, b.y));
                out_pb.move_to(p.0, p.1);
                out_pb.line_to(q.0, q.1);
            }
        }
        if let Some(path) = out_pb.finish() {
            let (r, g, b) = LEFT_OUT_RGB;
            let mut paint = Paint::default();
            paint.set_color_rgba8(r, g, b, 255);
            let stroke = Stroke {
                width: line_w * 2.0,
                line_cap: tiny_skia::LineCap::Round,
                ..Stroke::default()
            };
            pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
    if let Some(first) = moves.first() {
        let (x, y) = to_px(first.from.x, first.from.y);
        if let Some(c) = PathBuilder::from_circle(x, y, 3.0 * line_w) {
            let mut paint = Paint::default();
            paint.set_color_rgba8(30, 160, 60, 255);
            pm.fill_path(&c, &paint, FillRule::Winding, Transform::identity(), None);
        }
    }
    Ok((pm, stats))
}

/// The pieces of segment a-b outside the rectangle [0, w] x [0, h]
/// (Liang-Barsky: the inside is one parameter interval).
pub fn outside_pieces(a: Pt, b: Pt, w: f64, h: f64) -> Vec<(Pt, Pt)> {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, a.x), (dx, w - a.x), (-dy, a.y), (dy, h - a.y)] {
        if p == 0.0 {
            if q < 0.0 {
                return vec![(a, b)];
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if t0 >= t1 {
        return vec![(a, b)];
    }
    let at = |t: f64| Pt::new(a.x + t * dx, a.y + t * dy);
    let mut out = Vec::new();
    if t0 > 1e-12 {
        out.push((a, at(t0)));
    }
    if t1 < 1.0 - 1e-12 {
        out.push((at(t1), b));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath::parse;

    #[test]
    fn pieces_outside_the_travel() {
        let p = |x, y| Pt::new(x, y);
        assert!(outside_pieces(p(1.0, 1.0), p(5.0, 5.0), 10.0, 10.0).is_empty());
        assert_eq!(
            outside_pieces(p(-5.0, 5.0), p(15.0, 5.0), 10.0, 10.0),
            vec![(p(-5.0, 5.0), p(0.0, 5.0)), (p(10.0, 5.0), p(15.0, 5.0))]
        );
        let all = outside_pieces(p(-5.0, 20.0), p(15.0, 20.0), 10.0, 10.0);
        assert_eq!(all, vec![(p(-5.0, 20.0), p(15.0, 20.0))]);
    }

    #[test]
    fn strokes_and_travel_get_their_colours() {
        // Travel along the bottom edge, a drawn line along the top edge.
        let g = "G21 G90\nG0 X100 Y0\nG0 X0 Y50\nM3\nG1 X100 Y50 F1000\nM5\n";
        let moves = parse(g).unwrap();
        let (pm, st) = render(&moves, 400).unwrap();
        assert!((st.draw_mm - 100.0).abs() < 1e-9);
        assert!((st.travel_mm - (100.0 + 100f64.hypot(50.0))).abs() < 1e-9);
        let px = |x: u32, y: u32| pm.pixel(x, y).unwrap();
        // Top edge (y = 50 mm at pixel row 20) is blue, mid-row white.
        let top = px(200, 20);
        assert!(top.blue() > top.red() && top.alpha() == 255, "{top:?}");
        let mid = px(200, pm.height() / 2 + 30);
        assert_eq!((mid.red(), mid.green(), mid.blue()), (255, 255, 255));
        // Bottom edge has red dashes somewhere.
        let row = pm.height() - 20;
        assert!((20..380).any(|x| {
            let p = px(x, row);
            p.red() > 200 && p.green() < 200
        }));
    }
}
