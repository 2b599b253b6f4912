//! Polylines to circular arcs (G2/G3): runs of points that lie on one circle
//! within a tolerance become one arc, the rest stay lines. Works on the
//! flattened polyline rather than on the Béziers, so it serves every input
//! (SVG curves, Hershey glyphs, hatching) and its error is measured against
//! exactly what would otherwise be drawn.
//!
//! Greedy: from each point the arc is extended point by point while the
//! circle through its first, middle and last points keeps every point within
//! `tol`, every chord's bulge (the arc between two points leaves the
//! straight chord by its sagitta) within [`BULGE`] (or `tol` if larger: the
//! chords are themselves a flattening, 0.05 mm from the curve by default, and
//! the arc through their ends is nearer the curve than they are), and the
//! points turning one way, half a turn at most in all. The circle goes
//! exactly through both ends, so the G-code's end radius matches its start
//! radius (Grbl refuses an arc whose radii differ by more than 0.005 mm).

use crate::geom::Pt;

/// One piece of a stroke after its first point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Piece {
    Line(Pt),
    /// An arc to `to` about `centre`, counter-clockwise (G3) or not (G2).
    Arc {
        to: Pt,
        centre: Pt,
        ccw: bool,
    },
}

/// Longest run of points one arc may cover (bounds the work per point).
const MAX_RUN: usize = 400;
/// Largest bulge of the arc from a chord of the polyline (mm): the default
/// flattening tolerance of `svg`.
pub const BULGE: f64 = 0.05;

/// Largest radius emitted as an arc (mm): flatter runs stay lines.
const MAX_R: f64 = 5_000.0;

/// The stroke after its first point as lines and arcs within `tol` mm.
pub fn fit(s: &[Pt], tol: f64) -> Vec<Piece> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < s.len() {
        let mut best = None;
        let mut j = i + 2;
        while j < s.len() && j - i <= MAX_RUN {
            match arc_through(&s[i..=j], tol) {
                Some(a) => best = Some((j, a)),
                None => break,
            }
            j += 1;
        }
        match best {
            Some((j, (centre, ccw))) => {
                out.push(Piece::Arc {
                    to: s[j],
                    centre,
                    ccw,
                });
                i = j;
            }
            None => {
                out.push(Piece::Line(s[i + 1]));
                i += 1;
            }
        }
    }
    out
}

/// Centre and direction of the arc through `pts` (at least 3) within `tol`.
fn arc_through(pts: &[Pt], tol: f64) -> Option<(Pt, bool)> {
    let (a, b, c) = (pts[0], pts[pts.len() / 2], *pts.last()?);
    let centre = circumcentre(a, b, c)?;
    let r = a.dist(centre);
    if !(r.is_finite() && r <= MAX_R && r > tol) {
        return None;
    }
    let cross =
        |p: Pt, q: Pt| (p.x - centre.x) * (q.y - centre.y) - (p.y - centre.y) * (q.x - centre.x);
    let dot =
        |p: Pt, q: Pt| (p.x - centre.x) * (q.x - centre.x) + (p.y - centre.y) * (q.y - centre.y);
    let ccw = cross(a, b) + cross(b, c) > 0.0;
    let mut sweep = 0.0;
    for w in pts.windows(2) {
        let (p, q) = (w[0], w[1]);
        if (p.dist(centre) - r).abs() > tol {
            return None;
        }
        let x = cross(p, q);
        if (x > 0.0) != ccw || x == 0.0 {
            return None;
        }
        let step = x.abs().atan2(dot(p, q));
        if step >= std::f64::consts::PI {
            return None;
        }
        sweep += step;
        let half = p.dist(q) / 2.0;
        let sagitta = r - (r * r - half * half).max(0.0).sqrt();
        if sagitta > tol.max(BULGE) {
            return None;
        }
    }
    (sweep <= std::f64::consts::PI + 1e-9).then_some((centre, ccw))
}

fn circumcentre(a: Pt, b: Pt, c: Pt) -> Option<Pt> {
    let d = 2.0 * (a.x * (b.y - c.y) + b.x * (c.y - a.y) + c.x * (a.y - b.y));
    let scale = a.dist(b).max(b.dist(c)).max(a.dist(c));
    if d.abs() <= 1e-12 * scale * scale {
        return None;
    }
    let (a2, b2, c2) = (
        a.x * a.x + a.y * a.y,
        b.x * b.x + b.y * b.y,
        c.x * c.x + c.y * c.y,
    );
    Some(Pt::new(
        (a2 * (b.y - c.y) + b2 * (c.y - a.y) + c2 * (a.y - b.y)) / d,
        (a2 * (c.x - b.x) + b2 * (a.x - c.x) + c2 * (b.x - a.x)) / d,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle_pts(c: Pt, r: f64, a0: f64, a1: f64, n: usize) -> Vec<Pt> {
        (0..=n)
            .map(|k| {
                let a = a0 + (a1 - a0) * k as f64 / n as f64;
                Pt::new(c.x + r * a.cos(), c.y + r * a.sin())
            })
            .collect()
    }

    #[test]
    fn a_flattened_circle_becomes_few_arcs_on_the_circle() {
        let c = Pt::new(10.0, 20.0);
        let s = circle_pts(c, 15.0, 0.0, std::f64::consts::TAU, 200);
        let f = fit(&s, 0.01);
        assert_eq!(f.len(), 2, "two half circles: {f:?}");
        let mut from = s[0];
        for p in &f {
            let Piece::Arc { to, centre, ccw } = *p else {
                panic!("{p:?}")
            };
            assert!(ccw);
            assert!(centre.dist(c) < 0.01 && (from.dist(centre) - to.dist(centre)).abs() < 1e-9);
            from = to;
        }
        assert_eq!(from, s[200]);
        // Clockwise the other way round.
        let mut r = s.clone();
        r.reverse();
        assert!(fit(&r, 0.01)
            .iter()
            .all(|p| matches!(p, Piece::Arc { ccw: false, .. })));
    }

    #[test]
    fn corners_and_straight_runs_stay_lines() {
        // An L of two straight runs: nothing is an arc.
        let s: Vec<Pt> = (0..=10)
            .map(|k| Pt::new(k as f64, 0.0))
            .chain((1..=10).map(|k| Pt::new(10.0, k as f64)))
            .collect();
        let f = fit(&s, 0.05);
        assert!(f.iter().all(|p| matches!(p, Piece::Line(_))), "{f:?}");
        assert_eq!(f.len(), 20);
        // An S: two arcs of opposite turn, never one across the inflection.
        let mut s = circle_pts(Pt::new(0.0, 0.0), 10.0, std::f64::consts::PI, 0.0, 30);
        s.extend(
            circle_pts(
                Pt::new(20.0, 0.0),
                10.0,
                std::f64::consts::PI,
                std::f64::consts::TAU,
                30,
            )
            .into_iter()
            .skip(1),
        );
        let f = fit(&s, 0.01);
        let arcs: Vec<bool> = f
            .iter()
            .filter_map(|p| match p {
                Piece::Arc { ccw, .. } => Some(*ccw),
                _ => None,
            })
            .collect();
        assert_eq!(arcs, [false, true], "{f:?}");
    }
}
