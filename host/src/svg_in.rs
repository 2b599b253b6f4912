//! SVG to strokes. usvg does the SVG work (shapes to paths, transforms,
//! units, styles); this module walks its tree, applies each path's absolute
//! transform and flattens quadratic and cubic Béziers by adaptive
//! subdivision until every piece lies within the tolerance of its chord.
//! Output is in millimetres, y up (SVG y down is flipped about the page
//! height), so it feeds the planner and the G-code writer directly.

use crate::geom::{Pt, Stroke};
use anyhow::{Context, Result};
use usvg::tiny_skia_path::{PathSegment, Point, Transform};

/// CSS pixels (usvg's unit) to millimetres.
pub const MM_PER_PX: f64 = 25.4 / 96.0;

/// Strokes of every visible path in the SVG text, curves flattened so that
/// no point of a curve is farther than `tol_mm` from the polyline.
pub fn strokes_from_svg(text: &str, tol_mm: f64) -> Result<Vec<Stroke>> {
    let tree = usvg::Tree::from_str(text, &usvg::Options::default()).context("parsing SVG")?;
    let h = tree.size().height() as f64;
    let mut out = Vec::new();
    walk(tree.root(), tol_mm / MM_PER_PX, &mut out);
    for s in &mut out {
        for p in s.iter_mut() {
            *p = Pt::new(p.x * MM_PER_PX, (h - p.y) * MM_PER_PX);
        }
    }
    Ok(out)
}

fn walk(g: &usvg::Group, tol_px: f64, out: &mut Vec<Stroke>) {
    for node in g.children() {
        match node {
            usvg::Node::Group(g) => walk(g, tol_px, out),
            usvg::Node::Path(p) if p.is_visible() => {
                flatten_path(p.data(), p.abs_transform(), tol_px, out)
            }
            _ => {}
        }
    }
}

fn flatten_path(data: &usvg::tiny_skia_path::Path, ts: Transform, tol: f64, out: &mut Vec<Stroke>) {
    let map = |p: Point| {
        let mut q = [p];
        ts.map_points(&mut q);
        Pt::new(q[0].x as f64, q[0].y as f64)
    };
    let mut cur: Stroke = Vec::new();
    let mut start = Pt::new(0.0, 0.0);
    for seg in data.segments() {
        match seg {
            PathSegment::MoveTo(p) => {
                if cur.len() > 1 {
                    out.push(std::mem::take(&mut cur));
                }
                start = map(p);
                cur = vec![start];
            }
            PathSegment::LineTo(p) => cur.push(map(p)),
            PathSegment::QuadTo(c, p) => {
                let p0 = *cur.last().unwrap_or(&start);
                let c = map(c);
                let p3 = map(p);
                // Degree elevation: the quadratic as a cubic.
                let c1 = Pt::new(
                    p0.x + 2.0 / 3.0 * (c.x - p0.x),
                    p0.y + 2.0 / 3.0 * (c.y - p0.y),
                );
                let c2 = Pt::new(
                    p3.x + 2.0 / 3.0 * (c.x - p3.x),
                    p3.y + 2.0 / 3.0 * (c.y - p3.y),
                );
                flatten_cubic([p0, c1, c2, p3], tol, &mut cur);
            }
            PathSegment::CubicTo(c1, c2, p) => {
                let p0 = *cur.last().unwrap_or(&start);
                flatten_cubic([p0, map(c1), map(c2), map(p)], tol, &mut cur);
            }
            PathSegment::Close => {
                if cur.last() != Some(&start) {
                    cur.push(start);
                }
            }
        }
    }
    if cur.len() > 1 {
        out.push(cur);
    }
}

/// Appends points (after the first) of a cubic flattened within `tol`.
/// The curve lies in the convex hull of its control points, so once both
/// inner control points are within `tol` of the chord, so is the curve.
pub fn flatten_cubic(c: [Pt; 4], tol: f64, out: &mut Stroke) {
    flatten_rec(c, tol, out, 0);
}

fn flatten_rec(c: [Pt; 4], tol: f64, out: &mut Stroke, depth: u32) {
    if depth >= 24
        || (dist_to_segment(c[1], c[0], c[3]) <= tol && dist_to_segment(c[2], c[0], c[3]) <= tol)
    {
        out.push(c[3]);
        return;
    }
    let mid = |a: Pt, b: Pt| Pt::new((a.x + b.x) / 2.0, (a.y + b.y) / 2.0);
    let (p01, p12, p23) = (mid(c[0], c[1]), mid(c[1], c[2]), mid(c[2], c[3]));
    let (p012, p123) = (mid(p01, p12), mid(p12, p23));
    let m = mid(p012, p123);
    flatten_rec([c[0], p01, p012, m], tol, out, depth + 1);
    flatten_rec([m, p123, p23, c[3]], tol, out, depth + 1);
}

/// Distance from `p` to the segment a-b.
pub fn dist_to_segment(p: Pt, a: Pt, b: Pt) -> f64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    if len2 == 0.0 {
        return p.dist(a);
    }
    let t = (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0);
    p.dist(Pt::new(a.x + t * dx, a.y + t * dy))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dist_to_polyline(p: Pt, s: &[Pt]) -> f64 {
        s.windows(2)
            .map(|w| dist_to_segment(p, w[0], w[1]))
            .fold(f64::INFINITY, f64::min)
    }

    fn cubic_at(c: &[Pt; 4], t: f64) -> Pt {
        let u = 1.0 - t;
        let w = [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t];
        Pt::new(
            (0..4).map(|i| w[i] * c[i].x).sum(),
            (0..4).map(|i| w[i] * c[i].y).sum(),
        )
    }

    #[test]
    fn cubic_flattening_stays_within_tolerance() {
        let c = [
            Pt::new(0.0, 0.0),
            Pt::new(10.0, 40.0),
            Pt::new(50.0, -30.0),
            Pt::new(60.0, 5.0),
        ];
        for tol in [1.0, 0.1, 0.01] {
            let mut s = vec![c[0]];
            flatten_cubic(c, tol, &mut s);
            assert_eq!(*s.last().unwrap(), c[3]);
            for k in 0..=2000 {
                let d = dist_to_polyline(cubic_at(&c, k as f64 / 2000.0), &s);
                assert!(d <= tol + 1e-9, "tol {tol}: {d}");
            }
            // Coarser tolerance, fewer points.
            assert!(s.len() < 2000);
        }
    }

    #[test]
    fn shapes_and_transforms() {
        // 96 px = 25.4 mm. A 96x96 px page; a circle of r = 48 px at the
        // centre; a line moved by a translate; a rect as a closed stroke.
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="96" height="96">
            <circle cx="48" cy="48" r="48" fill="none" stroke="black"/>
            <g transform="translate(10 0)"><line x1="0" y1="0" x2="0" y2="96" stroke="black"/></g>
            <rect x="0" y="0" width="48" height="24" fill="none" stroke="black"/>
            <polyline points="0,0 10,10 20,0" fill="none" stroke="black"/>
            <ellipse cx="48" cy="48" rx="20" ry="10" fill="none" stroke="black"/>
            <path d="M 0 96 Q 48 0 96 96" fill="none" stroke="black"/>
        </svg>"#;
        let s = strokes_from_svg(svg, 0.01).unwrap();
        assert_eq!(s.len(), 6);
        let r = 12.7;
        for p in &s[0] {
            let d = p.dist(Pt::new(12.7, 12.7));
            // Within the flattening tolerance plus the cubic circle approximation.
            assert!((d - r).abs() < 0.01 + 3e-4 * r, "{d}");
        }
        assert!(s[0].len() > 16);
        let line = &s[1];
        assert_eq!(line.len(), 2);
        let x = 10.0 * MM_PER_PX;
        assert!((line[0].x - x).abs() < 1e-4 && (line[0].y - 25.4).abs() < 1e-4);
        assert!((line[1].x - x).abs() < 1e-4 && line[1].y.abs() < 1e-4);
        // The rect closes on itself: 5 points, first == last.
        assert_eq!(s[2].len(), 5);
        assert_eq!(s[2][0], s[2][4]);
        assert_eq!(s[3].len(), 3);
        // Quadratic: its apex (t = 0.5) is at y = 48 px, x = 48 px.
        let apex = Pt::new(48.0 * MM_PER_PX, 48.0 * MM_PER_PX);
        assert!(dist_to_polyline(apex, &s[5]) < 0.011);
    }
}
