//! G-code preview as PNG: pen-down strokes in dark blue, pen-up travel in
//! thin dashed red, the start as a green dot, fitted into the image with a
//! margin and y up like the machine. tiny-skia does the anti-aliased drawing.

use crate::toolpath::{Move, MoveKind};
use anyhow::{anyhow, Result};
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Stroke, StrokeDash, Transform};

pub struct Stats {
    pub draw_mm: f64,
    pub travel_mm: f64,
}

/// Renders the moves into a PNG of `width` pixels (height follows the aspect).
pub fn render(moves: &[Move], width: u32) -> Result<(Pixmap, Stats)> {
    let pts = moves.iter().flat_map(|m| [m.from, m.to]);
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for p in pts {
        lo = (lo.0.min(p.x), lo.1.min(p.y));
        hi = (hi.0.max(p.x), hi.1.max(p.y));
    }
    if moves.is_empty() {
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
    let mut stats = Stats {
        draw_mm: 0.0,
        travel_mm: 0.0,
    };
    let mut draw = PathBuilder::new();
    let mut travel = PathBuilder::new();
    for m in moves {
        let (pb, acc) = match m.kind {
            MoveKind::Draw => (&mut draw, &mut stats.draw_mm),
            MoveKind::Travel => (&mut travel, &mut stats.travel_mm),
        };
        *acc += m.from.dist(m.to);
        let a = to_px(m.from.x, m.from.y);
        let b = to_px(m.to.x, m.to.y);
        pb.move_to(a.0, a.1);
        pb.line_to(b.0, b.1);
    }
    let line_w = (width as f32 / 600.0).max(1.0);
    if let Some(path) = travel.finish() {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath::parse;

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
