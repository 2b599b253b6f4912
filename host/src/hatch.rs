//! Hatch fill: parallel lines `spacing` mm apart at `angle` degrees, clipped
//! to a shape given as closed rings (mm), inside by the SVG fill rule
//! (even-odd or nonzero winding), then joined into few strokes.
//!
//! Scanlines are placed on a global grid (multiples of the spacing in the
//! rotated frame) so neighbouring shapes hatch in step. Each line's crossings
//! with the ring edges, sorted, give the inside intervals by the rule. Joining
//! links a chain's last interval to one on the next line by a short connector
//! (at most three spacings) that stays inside the shape: it crosses no edge
//! and its midpoint is inside. The connector is ink inside the fill, so the
//! drawing still shows only the filled area.

use crate::geom::{Pt, Stroke};
use anyhow::{bail, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FillRule {
    EvenOdd,
    NonZero,
}

/// Most hatch lines one shape may get.
const MAX_LINES: f64 = 200_000.0;
/// Above this many (segments x edges) the connector checks are skipped and
/// the segments are left as they are (serpentine order).
const MAX_JOIN_WORK: f64 = 5e8;

/// Hatch lines clipped to `rings` (each closed or taken as closed).
pub fn hatch(
    rings: &[Stroke],
    rule: FillRule,
    spacing: f64,
    angle_deg: f64,
) -> Result<Vec<Stroke>> {
    if !(spacing.is_finite() && spacing > 0.0) {
        bail!("hatch spacing must be a positive number of mm");
    }
    if !angle_deg.is_finite() {
        bail!("hatch angle must be a number of degrees");
    }
    let (s, c) = angle_deg.to_radians().sin_cos();
    // To the frame where hatch lines are horizontal, and back.
    let fwd = |p: Pt| Pt::new(p.x * c + p.y * s, -p.x * s + p.y * c);
    let back = |p: Pt| Pt::new(p.x * c - p.y * s, p.x * s + p.y * c);
    let mut edges: Vec<(Pt, Pt)> = Vec::new();
    for r in rings.iter().filter(|r| r.len() > 1) {
        let pts: Vec<Pt> = r.iter().map(|&p| fwd(p)).collect();
        for w in pts.windows(2) {
            edges.push((w[0], w[1]));
        }
        if let (Some(&a), Some(&b)) = (pts.last(), pts.first()) {
            if a != b {
                edges.push((a, b));
            }
        }
    }
    if edges.is_empty() {
        return Ok(Vec::new());
    }
    let vmin = edges
        .iter()
        .map(|e| e.0.y.min(e.1.y))
        .fold(f64::INFINITY, f64::min);
    let vmax = edges
        .iter()
        .map(|e| e.0.y.max(e.1.y))
        .fold(f64::NEG_INFINITY, f64::max);
    let (k0, k1) = ((vmin / spacing).ceil(), (vmax / spacing).floor());
    if k1 - k0 > MAX_LINES {
        bail!(
            "{} hatch lines for one shape (spacing {spacing} mm): choose a larger spacing",
            k1 - k0
        );
    }
    // Inside intervals per scanline.
    let mut rows: Vec<(f64, Vec<(f64, f64)>)> = Vec::new();
    let mut k = k0;
    while k <= k1 {
        let v = k * spacing;
        let mut xs: Vec<(f64, i32)> = edges
            .iter()
            .filter_map(|&(a, b)| {
                let (lo, hi) = if a.y < b.y { (a, b) } else { (b, a) };
                if a.y == b.y || v < lo.y || v >= hi.y {
                    return None;
                }
                let u = lo.x + (v - lo.y) * (hi.x - lo.x) / (hi.y - lo.y);
                Some((u, if b.y > a.y { 1 } else { -1 }))
            })
            .collect();
        xs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut wind = 0;
        let mut segs = Vec::new();
        for w in xs.windows(2) {
            wind += w[0].1;
            let inside = match rule {
                FillRule::EvenOdd => wind % 2 != 0,
                FillRule::NonZero => wind != 0,
            };
            if inside && w[1].0 > w[0].0 {
                // Merge with the previous interval when they touch.
                match segs.last_mut() {
                    Some((_, e)) if *e == w[0].0 => *e = w[1].0,
                    _ => segs.push((w[0].0, w[1].0)),
                }
            }
        }
        rows.push((v, segs));
        k += 1.0;
    }
    let nsegs: usize = rows.iter().map(|r| r.1.len()).sum();
    let join = nsegs as f64 * edges.len() as f64 <= MAX_JOIN_WORK;
    let inside = |p: Pt| {
        let mut wind = 0;
        for &(a, b) in &edges {
            let (lo, hi) = if a.y < b.y { (a, b) } else { (b, a) };
            if a.y == b.y || p.y < lo.y || p.y >= hi.y {
                continue;
            }
            let u = lo.x + (p.y - lo.y) * (hi.x - lo.x) / (hi.y - lo.y);
            if u < p.x {
                wind += if b.y > a.y { 1 } else { -1 };
            }
        }
        match rule {
            FillRule::EvenOdd => wind % 2 != 0,
            FillRule::NonZero => wind != 0,
        }
    };
    let scale = edges
        .iter()
        .map(|e| e.0.x.abs().max(e.0.y.abs()))
        .fold(1.0, f64::max);
    let on_edge = |p: Pt| {
        edges
            .iter()
            .any(|&(a, b)| crate::svg_in::dist_to_segment(p, a, b) <= 1e-9 * scale)
    };
    // A connector is ink: it must stay in the fill (on its boundary is fine).
    let clear = |p: Pt, q: Pt| {
        let m = Pt::new((p.x + q.x) / 2.0, (p.y + q.y) / 2.0);
        edges.iter().all(|&(a, b)| !crosses(p, q, a, b)) && (inside(m) || on_edge(m))
    };
    // Chains: (points, row index of the last point).
    let mut chains: Vec<(Vec<Pt>, usize)> = Vec::new();
    for (ri, (v, segs)) in rows.iter().enumerate() {
        let mut taken = vec![false; chains.len()];
        for &(a, b) in segs {
            let (pa, pb) = (Pt::new(a, *v), Pt::new(b, *v));
            let mut best: Option<(f64, usize, bool)> = None;
            if join && ri > 0 {
                for (ci, (pts, last)) in chains.iter().enumerate() {
                    if *last + 1 != ri || taken[ci] {
                        continue;
                    }
                    let Some(&e) = pts.last() else { continue };
                    for (end, rev) in [(pa, false), (pb, true)] {
                        let d = e.dist(end);
                        if d <= 3.0 * spacing && best.is_none_or(|b| d < b.0) && clear(e, end) {
                            best = Some((d, ci, rev));
                        }
                    }
                }
            }
            match best {
                Some((_, ci, rev)) => {
                    let (first, second) = if rev { (pb, pa) } else { (pa, pb) };
                    chains[ci].0.extend([first, second]);
                    chains[ci].1 = ri;
                    taken[ci] = true;
                }
                None => {
                    // Serpentine: odd rows right to left.
                    let pts = if ri % 2 == 1 {
                        vec![pb, pa]
                    } else {
                        vec![pa, pb]
                    };
                    chains.push((pts, ri));
                    taken.push(true);
                }
            }
        }
    }
    Ok(chains
        .into_iter()
        .map(|(pts, _)| pts.into_iter().map(back).collect())
        .collect())
}

/// Whether segments p-q and a-b cross at a point inside both (touching at
/// an end does not count: connectors end on the boundary).
fn crosses(p: Pt, q: Pt, a: Pt, b: Pt) -> bool {
    let o = |a: Pt, b: Pt, c: Pt| (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    let (d1, d2) = (o(a, b, p), o(a, b, q));
    let (d3, d4) = (o(p, q, a), o(p, q, b));
    let eps = 1e-12 * (1.0 + p.x.abs() + p.y.abs() + q.x.abs() + q.y.abs());
    ((d1 > eps && d2 < -eps) || (d1 < -eps && d2 > eps))
        && ((d3 > eps && d4 < -eps) || (d3 < -eps && d4 > eps))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pen_down_length;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Stroke {
        vec![
            Pt::new(x0, y0),
            Pt::new(x1, y0),
            Pt::new(x1, y1),
            Pt::new(x0, y1),
            Pt::new(x0, y0),
        ]
    }

    #[test]
    fn a_square_is_one_zigzag_inside_the_square() {
        let h = hatch(&[rect(0.0, 0.0, 10.0, 10.0)], FillRule::NonZero, 1.0, 0.0).unwrap();
        assert_eq!(h.len(), 1, "{h:?}");
        // Lines at y = 0..=9 (y = 10 is the top edge, half-open): 10 lines of 10 mm.
        let horizontal: f64 = h[0]
            .windows(2)
            .filter(|w| (w[0].y - w[1].y).abs() < 1e-9)
            .map(|w| w[0].dist(w[1]))
            .sum();
        assert!((horizontal - 100.0).abs() < 1e-9, "{horizontal}");
        for p in &h[0] {
            assert!(p.x >= -1e-9 && p.x <= 10.0 + 1e-9 && p.y >= -1e-9 && p.y <= 10.0);
        }
    }

    #[test]
    fn a_hole_stays_empty_by_either_rule_when_wound_back() {
        let outer = rect(0.0, 0.0, 10.0, 10.0);
        let mut hole = rect(3.0, 3.0, 7.0, 7.0);
        // Same winding: even-odd leaves a hole, nonzero fills it.
        let eo = hatch(&[outer.clone(), hole.clone()], FillRule::EvenOdd, 0.5, 0.0).unwrap();
        let nz = hatch(&[outer.clone(), hole.clone()], FillRule::NonZero, 0.5, 0.0).unwrap();
        let in_hole = |h: &[Stroke]| {
            h.iter().any(|s| {
                s.windows(2).any(|w| {
                    let m = Pt::new((w[0].x + w[1].x) / 2.0, (w[0].y + w[1].y) / 2.0);
                    m.x > 3.1 && m.x < 6.9 && m.y > 3.1 && m.y < 6.9
                })
            })
        };
        assert!(!in_hole(&eo));
        assert!(in_hole(&nz));
        // Hole wound the other way: nonzero leaves it empty too.
        hole.reverse();
        let nz2 = hatch(&[outer, hole], FillRule::NonZero, 0.5, 0.0).unwrap();
        assert!(!in_hole(&nz2));
        assert!(pen_down_length(&eo) < pen_down_length(&nz));
    }

    #[test]
    fn angle_turns_the_lines_and_spacing_sets_their_count() {
        let h = hatch(&[rect(0.5, 0.5, 20.5, 20.5)], FillRule::EvenOdd, 2.0, 90.0).unwrap();
        // Vertical lines: the long pieces run along y.
        let vertical = h
            .iter()
            .flat_map(|s| s.windows(2))
            .filter(|w| (w[0].x - w[1].x).abs() < 1e-9 && (w[0].y - w[1].y).abs() > 19.0)
            .count();
        assert_eq!(vertical, 10);
        assert!(hatch(&[rect(0.0, 0.0, 1.0, 1.0)], FillRule::EvenOdd, 0.0, 0.0).is_err());
        assert!(hatch(&[rect(0.0, 0.0, 1e9, 1e9)], FillRule::EvenOdd, 0.001, 0.0).is_err());
    }
}
