//! Curves to arcs: a cubic Bézier (SVG's curves; quadratics are raised to cubics,
//! ellipse arcs arrive as cubics) as circular arcs within a tolerance, for
//! `cargo host svg --arcs`.
//!
//! Each cubic is approximated by a biarc: two arcs that meet with one tangent,
//! leaving the curve's start along its start tangent and reaching its end along
//! its end tangent (the junction is placed by the equal-distance rule: both
//! tangent lines are followed the same distance α). The biarc is measured against
//! the curve both ways (points of the curve to the arcs, points of the arcs to the
//! curve); a piece further than the tolerance is split in two at its middle (de
//! Casteljau) and each half fitted again. Then neighbouring arcs that one circle
//! holds within the tolerance are merged (a circle drawn as four cubics comes out
//! as two arcs). Consecutive pieces share their tangent, so the pen never turns a
//! corner the drawing does not have.
//!
//! The arcs travel with the stroke as its points (so route planning may reorder and
//! reverse strokes as it likes) and an [`ArcHints`] table: for a pair of
//! consecutive points, the centre and the direction of the arc between them. The
//! G-code writer looks each pair up; a reversed pair is the same arc run the other
//! way (G2 for G3).

use crate::geom::Pt;
use std::collections::HashMap;

/// A piece of a curve after its start point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Seg {
    Line(Pt),
    /// An arc to `to` about `centre`, counter-clockwise (G3) or not (G2).
    Arc {
        to: Pt,
        centre: Pt,
        ccw: bool,
    },
}

/// Largest radius sent as an arc (mm): flatter pieces go as lines.
const MAX_R: f64 = 5_000.0;
/// Deepest split of one cubic (2^12 pieces at most).
const MAX_DEPTH: u32 = 12;
/// Points sampled along each side when a biarc is measured against its curve.
const SAMPLES: usize = 16;
/// Cosine of the largest turn a merge may put where arcs meet (1 degree).
const TANGENT_COS: f64 = 0.999_85;
/// Largest sweep of one merged arc (radians): far from a full turn, whose end
/// point is its start.
const MAX_SWEEP: f64 = 1.5 * std::f64::consts::PI;

fn sub(a: Pt, b: Pt) -> Pt {
    Pt::new(a.x - b.x, a.y - b.y)
}
fn add(a: Pt, b: Pt) -> Pt {
    Pt::new(a.x + b.x, a.y + b.y)
}
fn mul(a: Pt, k: f64) -> Pt {
    Pt::new(a.x * k, a.y * k)
}
fn dot(a: Pt, b: Pt) -> f64 {
    a.x * b.x + a.y * b.y
}
fn cross(a: Pt, b: Pt) -> f64 {
    a.x * b.y - a.y * b.x
}
fn unit(a: Pt) -> Option<Pt> {
    let n = a.x.hypot(a.y);
    (n > 1e-12 && n.is_finite()).then(|| mul(a, 1.0 / n))
}
fn mid(a: Pt, b: Pt) -> Pt {
    mul(add(a, b), 0.5)
}

/// The point of the cubic at `t`.
pub fn cubic_at(c: &[Pt; 4], t: f64) -> Pt {
    let u = 1.0 - t;
    let (a, b, cc, d) = (u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t);
    Pt::new(
        a * c[0].x + b * c[1].x + cc * c[2].x + d * c[3].x,
        a * c[0].y + b * c[1].y + cc * c[2].y + d * c[3].y,
    )
}

/// The cubic's two halves.
fn split(c: &[Pt; 4]) -> ([Pt; 4], [Pt; 4]) {
    let (p01, p12, p23) = (mid(c[0], c[1]), mid(c[1], c[2]), mid(c[2], c[3]));
    let (p012, p123) = (mid(p01, p12), mid(p12, p23));
    let m = mid(p012, p123);
    ([c[0], p01, p012, m], [m, p123, p23, c[3]])
}

/// One arc or line from `from`: its end, and the arc's centre and direction.
#[derive(Clone, Copy, Debug)]
struct Piece {
    from: Pt,
    seg: Seg,
}

impl Piece {
    fn to(&self) -> Pt {
        match self.seg {
            Seg::Line(p) | Seg::Arc { to: p, .. } => p,
        }
    }

    /// Sweep of an arc (radians, positive), 0 for a line.
    fn sweep(&self) -> f64 {
        match self.seg {
            Seg::Line(_) => 0.0,
            Seg::Arc { to, centre, ccw } => sweep(self.from, to, centre, ccw),
        }
    }

    /// The point `k` of `n` along the piece.
    fn at(&self, k: usize, n: usize) -> Pt {
        let f = k as f64 / n as f64;
        match self.seg {
            Seg::Line(p) => add(self.from, mul(sub(p, self.from), f)),
            Seg::Arc { centre, ccw, .. } => {
                let a0 = (self.from.y - centre.y).atan2(self.from.x - centre.x);
                let s = self.sweep() * f * if ccw { 1.0 } else { -1.0 };
                let r = self.from.dist(centre);
                Pt::new(centre.x + r * (a0 + s).cos(), centre.y + r * (a0 + s).sin())
            }
        }
    }

    /// Unit tangent (direction of travel) at its start and at its end.
    fn tangents(&self) -> Option<(Pt, Pt)> {
        match self.seg {
            Seg::Line(p) => {
                let t = unit(sub(p, self.from))?;
                Some((t, t))
            }
            Seg::Arc { to, centre, ccw } => {
                let turn = |p: Pt| {
                    let r = unit(sub(p, centre))?;
                    Some(if ccw {
                        Pt::new(-r.y, r.x)
                    } else {
                        Pt::new(r.y, -r.x)
                    })
                };
                Some((turn(self.from)?, turn(to)?))
            }
        }
    }

    /// Distance from `p` to the piece.
    fn dist(&self, p: Pt) -> f64 {
        let to = self.to();
        match self.seg {
            Seg::Line(_) => crate::svg_in::dist_to_segment(p, self.from, to),
            Seg::Arc { centre, ccw, .. } => {
                let ends = p.dist(self.from).min(p.dist(to));
                let into = sweep(self.from, p, centre, ccw);
                if into <= self.sweep() {
                    let r = self.from.dist(centre);
                    (p.dist(centre) - r).abs().min(ends)
                } else {
                    ends
                }
            }
        }
    }
}

/// Angle swept from `a` to `b` about `c` in the arc's direction, in [0, 2 pi).
fn sweep(a: Pt, b: Pt, c: Pt, ccw: bool) -> f64 {
    let (a0, a1) = ((a.y - c.y).atan2(a.x - c.x), (b.y - c.y).atan2(b.x - c.x));
    let d = if ccw { a1 - a0 } else { a0 - a1 };
    d.rem_euclid(std::f64::consts::TAU)
}

/// The arc from `from` leaving along unit tangent `t` that ends at `to` (a line if
/// it is straight or its radius beyond [`MAX_R`]).
fn arc_from(from: Pt, t: Pt, to: Pt) -> Piece {
    let n = Pt::new(-t.y, t.x);
    let w = sub(to, from);
    let nw = dot(n, w);
    let s = if nw.abs() > 1e-12 {
        dot(w, w) / (2.0 * nw)
    } else {
        f64::INFINITY
    };
    let seg = if s.abs() <= MAX_R {
        Seg::Arc {
            to,
            centre: add(from, mul(n, s)),
            ccw: s > 0.0,
        }
    } else {
        Seg::Line(to)
    };
    Piece { from, seg }
}

/// The arc that ends at `to` arriving along unit tangent `t`, from `from`.
fn arc_to(from: Pt, to: Pt, t: Pt) -> Piece {
    // The same circle run backwards from `to` along -t, then turned round.
    match arc_from(to, mul(t, -1.0), from).seg {
        Seg::Arc { centre, ccw, .. } => Piece {
            from,
            seg: Seg::Arc {
                to,
                centre,
                ccw: !ccw,
            },
        },
        Seg::Line(_) => Piece {
            from,
            seg: Seg::Line(to),
        },
    }
}

/// The biarc of the cubic: one or two pieces, or None if its tangents are not
/// defined (all control points together).
fn biarc(c: &[Pt; 4]) -> Option<Vec<Piece>> {
    let (p0, p1) = (c[0], c[3]);
    let t0 = unit(sub(c[1], c[0]))
        .or_else(|| unit(sub(c[2], c[0])))
        .or_else(|| unit(sub(c[3], c[0])))?;
    let t1 = unit(sub(c[3], c[2]))
        .or_else(|| unit(sub(c[3], c[1])))
        .or_else(|| unit(sub(c[3], c[0])))?;
    let d = sub(p1, p0);
    let dd = dot(d, d);
    if dd < 1e-18 {
        return None;
    }
    // Straight on: tangents along the chord.
    if cross(t0, d).abs() < 1e-9 * dd.sqrt() && cross(t1, d).abs() < 1e-9 * dd.sqrt() {
        return Some(vec![Piece {
            from: p0,
            seg: Seg::Line(p1),
        }]);
    }
    let v = add(t0, t1);
    let vd = dot(v, d);
    let denom = 2.0 * (1.0 - dot(t0, t1));
    let alpha = if denom.abs() < 1e-12 {
        // Parallel tangents: the junction halfway.
        let td = dot(t1, d);
        if td.abs() < 1e-12 {
            return None;
        }
        dd / (4.0 * td)
    } else {
        (-vd + (vd * vd + denom * dd).sqrt()) / denom
    };
    if !alpha.is_finite() || alpha <= 0.0 {
        return None;
    }
    let j = mid(add(p0, mul(t0, alpha)), sub(p1, mul(t1, alpha)));
    Some(vec![arc_from(p0, t0, j), arc_to(j, p1, t1)])
}

/// How far apart the pieces and the curve are: the larger of the farthest curve
/// point from the pieces and the farthest piece point from the curve (the
/// latter against the curve sampled finely).
fn error(c: &[Pt; 4], pieces: &[Piece]) -> f64 {
    let near = |p: Pt| {
        pieces
            .iter()
            .map(|q| q.dist(p))
            .fold(f64::INFINITY, f64::min)
    };
    let mut e = (0..=SAMPLES)
        .map(|k| near(cubic_at(c, k as f64 / SAMPLES as f64)))
        .fold(0.0, f64::max);
    let fine: Vec<Pt> = (0..=4 * SAMPLES)
        .map(|k| cubic_at(c, k as f64 / (4 * SAMPLES) as f64))
        .collect();
    for q in pieces {
        for k in 1..SAMPLES {
            let p = q.at(k, SAMPLES);
            let d = fine
                .windows(2)
                .map(|w| crate::svg_in::dist_to_segment(p, w[0], w[1]))
                .fold(f64::INFINITY, f64::min);
            e = e.max(d);
        }
    }
    e
}

/// A fitted piece with the curve points it stands for (to check a merge).
struct Fitted {
    piece: Piece,
    curve: Vec<Pt>,
}

fn fit_rec(c: &[Pt; 4], tol: f64, depth: u32, out: &mut Vec<Fitted>) {
    let curve = || -> Vec<Pt> {
        (0..=SAMPLES)
            .map(|k| cubic_at(c, k as f64 / SAMPLES as f64))
            .collect()
    };
    if let Some(pieces) = biarc(c) {
        if error(c, &pieces) <= tol {
            // Each piece keeps the curve points it stands for (the nearer one's).
            let pts = curve();
            for (k, piece) in pieces.iter().enumerate() {
                let mine = pts
                    .iter()
                    .filter(|&&p| {
                        let d = piece.dist(p);
                        pieces
                            .iter()
                            .enumerate()
                            .all(|(j, q)| j == k || d <= q.dist(p))
                    })
                    .copied()
                    .collect();
                out.push(Fitted {
                    piece: *piece,
                    curve: mine,
                });
            }
            return;
        }
    }
    if depth >= MAX_DEPTH || c[0].dist(c[3]) + c[1].dist(c[0]) + c[2].dist(c[3]) <= tol * 0.25 {
        out.push(Fitted {
            piece: Piece {
                from: c[0],
                seg: Seg::Line(c[3]),
            },
            curve: curve(),
        });
        return;
    }
    let (a, b) = split(c);
    fit_rec(&a, tol, depth + 1, out);
    fit_rec(&b, tol, depth + 1, out);
}

/// The circle through three points, if they are not in line.
fn circle3(a: Pt, b: Pt, c: Pt) -> Option<Pt> {
    let (ab, ac) = (sub(b, a), sub(c, a));
    let d = 2.0 * cross(ab, ac);
    if d.abs() < 1e-12 {
        return None;
    }
    let (l1, l2) = (dot(ab, ab), dot(ac, ac));
    let centre = add(
        a,
        Pt::new((ac.y * l1 - ab.y * l2) / d, (ab.x * l2 - ac.x * l1) / d),
    );
    (centre.dist(a) <= MAX_R).then_some(centre)
}

/// Merges neighbouring arcs that one arc through their outer ends and their
/// junction holds within `tol` of all their curve points.
fn merge(fitted: Vec<Fitted>, tol: f64) -> Vec<Seg> {
    let mut out: Vec<Fitted> = Vec::new();
    for f in fitted {
        if let Some(last) = out.last_mut() {
            if let (Seg::Arc { ccw: c0, .. }, Seg::Arc { ccw: c1, .. }) =
                (last.piece.seg, f.piece.seg)
            {
                let (a, b, e) = (last.piece.from, last.piece.to(), f.piece.to());
                if c0 == c1 {
                    if let Some(centre) = circle3(a, b, e) {
                        let joined = Piece {
                            from: a,
                            seg: Seg::Arc {
                                to: e,
                                centre,
                                ccw: c0,
                            },
                        };
                        // The joined arc must leave and arrive as the two did: no
                        // corner where it meets its neighbours (1 degree at most).
                        let same_ends =
                            match (last.piece.tangents(), f.piece.tangents(), joined.tangents()) {
                                (Some((s0, _)), Some((_, e1)), Some((js, je))) => {
                                    dot(s0, js) > TANGENT_COS && dot(e1, je) > TANGENT_COS
                                }
                                _ => false,
                            };
                        let fits = same_ends
                            && joined.sweep() <= MAX_SWEEP
                            && sweep(a, b, centre, c0) <= joined.sweep()
                            && last
                                .curve
                                .iter()
                                .chain(&f.curve)
                                .all(|&p| joined.dist(p) <= tol);
                        if fits {
                            last.piece = joined;
                            last.curve.extend(f.curve);
                            continue;
                        }
                    }
                }
            }
        }
        out.push(f);
    }
    out.into_iter().map(|f| f.piece.seg).collect()
}

/// What the fit aims at, of the tolerance asked: the checks sample the curve, so
/// between samples the distance may be a little larger.
const MARGIN: f64 = 0.9;

/// The cubic as lines and arcs within `tol` (mm), after its start point.
pub fn fit_cubic(c: [Pt; 4], tol: f64) -> Vec<Seg> {
    fit_cubics(&[c], tol)
}

/// Several cubics in a row (one subpath), merged across their joins too.
pub fn fit_cubics(cs: &[[Pt; 4]], tol: f64) -> Vec<Seg> {
    let mut fitted = Vec::new();
    for c in cs {
        fit_rec(c, tol * MARGIN, 0, &mut fitted);
    }
    merge(fitted, tol * MARGIN)
}

/// The arcs between consecutive stroke points, by their end points.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ArcHints(HashMap<[u64; 4], (Pt, bool)>);

fn key(a: Pt, b: Pt) -> [u64; 4] {
    [a.x.to_bits(), a.y.to_bits(), b.x.to_bits(), b.y.to_bits()]
}

impl ArcHints {
    /// Records the arc from `from` to `to`.
    pub fn insert(&mut self, from: Pt, to: Pt, centre: Pt, ccw: bool) {
        self.0.insert(key(from, to), (centre, ccw));
    }

    /// The arc from `from` to `to`: its centre and direction (a pair recorded the
    /// other way round is the same arc run backwards).
    pub fn get(&self, from: Pt, to: Pt) -> Option<(Pt, bool)> {
        if let Some(&h) = self.0.get(&key(from, to)) {
            return Some(h);
        }
        self.0.get(&key(to, from)).map(|&(c, ccw)| (c, !ccw))
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn len(&self) -> usize {
        self.0.len()
    }

    pub fn extend(&mut self, other: ArcHints) {
        self.0.extend(other.0);
    }

    /// The same arcs after the drawing is scaled by `k` (> 0) and moved by `off`,
    /// as the strokes are (`p * k + off`, so the keys match the moved points).
    pub fn scale_move(&mut self, k: f64, off: Pt) {
        let f =
            |x: u64, y: u64| Pt::new(f64::from_bits(x) * k + off.x, f64::from_bits(y) * k + off.y);
        self.0 = std::mem::take(&mut self.0)
            .into_iter()
            .map(|(kk, (c, ccw))| {
                let (a, b) = (f(kk[0], kk[1]), f(kk[2], kk[3]));
                (key(a, b), (Pt::new(c.x * k + off.x, c.y * k + off.y), ccw))
            })
            .collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Largest distance between the fitted pieces and the curve, both ways.
    fn worst(c: &[Pt; 4], segs: &[Seg]) -> f64 {
        let mut pieces = Vec::new();
        let mut from = c[0];
        for &s in segs {
            let p = Piece { from, seg: s };
            from = p.to();
            pieces.push(p);
        }
        assert!(from.dist(c[3]) < 1e-9, "ends at the curve's end");
        let n = 400;
        let near = |p: Pt| {
            pieces
                .iter()
                .map(|q| q.dist(p))
                .fold(f64::INFINITY, f64::min)
        };
        let fine: Vec<Pt> = (0..=n).map(|k| cubic_at(c, k as f64 / n as f64)).collect();
        let mut e = fine.iter().map(|&p| near(p)).fold(0.0, f64::max);
        for q in &pieces {
            for k in 0..=50 {
                let p = q.at(k, 50);
                let d = fine
                    .windows(2)
                    .map(|w| crate::svg_in::dist_to_segment(p, w[0], w[1]))
                    .fold(f64::INFINITY, f64::min);
                e = e.max(d);
            }
        }
        e
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// Any cubic: the arcs stay within the tolerance of the curve and the curve
        /// of the arcs (sampled far finer than the fit), the pieces join end to end
        /// with one tangent, and each radius is the same at both ends.
        #[test]
        fn arcs_stay_within_the_tolerance_of_any_cubic(
            pts in proptest::array::uniform8(-50.0f64..50.0),
            tol in prop_oneof![Just(0.01), Just(0.05), Just(0.2)],
        ) {
            let c = [
                Pt::new(pts[0], pts[1]),
                Pt::new(pts[2], pts[3]),
                Pt::new(pts[4], pts[5]),
                Pt::new(pts[6], pts[7]),
            ];
            prop_assume!(c[0].dist(c[3]) > 0.1);
            let segs = fit_cubic(c, tol);
            // The fit samples the curve 16 times a piece, this check 400 times.
            let e = worst(&c, &segs);
            prop_assert!(e <= tol, "{e} mm off with tolerance {tol}");
            let mut from = c[0];
            let mut last_t: Option<Pt> = None;
            for &s in &segs {
                let (t0, t1) = Piece { from, seg: s }.tangents().unwrap();
                if let Some(lt) = last_t {
                    // Subdivision keeps the curve's tangent at every join; lines
                    // from degenerate pieces may bend by a little.
                    prop_assert!(dot(lt, t0) > 0.99, "a corner between pieces: {lt:?} {t0:?}");
                }
                if let Seg::Arc { to, centre, .. } = s {
                    prop_assert!((from.dist(centre) - to.dist(centre)).abs() < 1e-6);
                }
                last_t = Some(t1);
                from = match s { Seg::Line(p) | Seg::Arc { to: p, .. } => p };
            }
        }
    }

    #[test]
    fn a_circle_drawn_as_four_cubics_is_at_most_two_arcs() {
        let k = 0.552_284_749_831 * 10.0;
        let (cx, cy) = (30.0, 20.0);
        let p = |x: f64, y: f64| Pt::new(cx + x, cy + y);
        let quarters = [
            [p(10.0, 0.0), p(10.0, k), p(k, 10.0), p(0.0, 10.0)],
            [p(0.0, 10.0), p(-k, 10.0), p(-10.0, k), p(-10.0, 0.0)],
            [p(-10.0, 0.0), p(-10.0, -k), p(-k, -10.0), p(0.0, -10.0)],
            [p(0.0, -10.0), p(k, -10.0), p(10.0, -k), p(10.0, 0.0)],
        ];
        let segs = fit_cubics(&quarters, 0.01);
        assert!(segs.len() <= 2, "{segs:?}");
        for s in &segs {
            let Seg::Arc { centre, ccw, .. } = *s else {
                panic!("a line in a circle: {segs:?}")
            };
            assert!(ccw);
            assert!(centre.dist(Pt::new(cx, cy)) < 0.01, "{centre:?}");
        }
    }

    #[test]
    fn a_straight_cubic_is_one_line_and_a_quarter_ellipse_a_few_arcs() {
        let line = fit_cubic(
            [
                Pt::new(0.0, 0.0),
                Pt::new(1.0, 1.0),
                Pt::new(2.0, 2.0),
                Pt::new(3.0, 3.0),
            ],
            0.01,
        );
        assert_eq!(line, vec![Seg::Line(Pt::new(3.0, 3.0))]);
        // A quarter of an ellipse 40 x 10 mm as its usual cubic.
        let k = 0.552_284_749_831;
        let c = [
            Pt::new(40.0, 0.0),
            Pt::new(40.0, 10.0 * k),
            Pt::new(40.0 * k, 10.0),
            Pt::new(0.0, 10.0),
        ];
        let segs = fit_cubic(c, 0.05);
        assert!(segs.len() <= 8, "{} pieces", segs.len());
        assert!(worst(&c, &segs) <= 0.05);
    }

    #[test]
    fn a_reversed_pair_is_the_same_arc_run_backwards() {
        let mut h = ArcHints::default();
        let (a, b, c) = (Pt::new(1.0, 0.0), Pt::new(0.0, 1.0), Pt::new(0.0, 0.0));
        h.insert(a, b, c, true);
        assert_eq!(h.get(a, b), Some((c, true)));
        assert_eq!(h.get(b, a), Some((c, false)));
        assert_eq!(h.get(a, c), None);
    }
}
