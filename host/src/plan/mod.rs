//! Pen-path planning: the one entry point that turns strokes in any order
//! into strokes in drawing order. Euler joining first (strokes meeting at
//! junctions become single trails), then ordering and orientation. The
//! result is never worse than the strokes as given: if the search loses to
//! the natural order (it cannot, but the guard makes it a guarantee), the
//! natural order is returned. Closed strokes are then rotated to start at
//! their best vertex, and strokes that meet exactly are drawn as one.

pub mod euler;
pub mod order;

use crate::geom::{pen_up_travel, Pt, Stroke};
pub use order::Effort;

#[derive(Clone, Copy, Debug)]
pub struct PlanOptions {
    /// Strokes may be drawn backwards (off keeps calligraphic direction).
    pub reverse: bool,
    /// Join strokes that share end points with Euler walks.
    pub join: bool,
    /// End points closer than this (drawing units) are one junction.
    pub join_tol: f64,
    pub effort: Effort,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            reverse: true,
            join: true,
            join_tol: 1e-3,
            effort: Effort::default(),
        }
    }
}

/// Orders (and orients, joins) strokes to reduce pen-up travel from `start`.
pub fn plan(strokes: &[Stroke], start: Pt, opt: &PlanOptions) -> Vec<Stroke> {
    let strokes: Vec<Stroke> = strokes.iter().filter(|s| !s.is_empty()).cloned().collect();
    let joined = if opt.join {
        euler::join(&strokes, opt.join_tol, opt.reverse)
    } else {
        strokes.clone()
    };
    let mut planned = order_strokes(&joined, start, opt.reverse, opt.effort);
    rotate_loops(&mut planned, start);
    if opt.join {
        planned = merge_touching(planned);
    }
    if pen_up_travel(&planned, start) <= pen_up_travel(&strokes, start) {
        planned
    } else {
        strokes
    }
}

/// A closed stroke (first point == last) can be drawn from any of its
/// vertices: start each one at the vertex nearest to the pen coming in and
/// the next stroke going out. Each change lowers the travel, so this only
/// improves; two passes let neighbouring loops settle.
pub fn rotate_loops(strokes: &mut [Stroke], start: Pt) {
    for _ in 0..2 {
        for k in 0..strokes.len() {
            let s = &strokes[k];
            if s.len() < 3 || s.first() != s.last() {
                continue;
            }
            let before = if k == 0 {
                start
            } else {
                *strokes[k - 1].last().unwrap()
            };
            let after = strokes.get(k + 1).map(|n| n[0]);
            let cost = |p: Pt| before.dist(p) + after.map_or(0.0, |a| p.dist(a));
            let best = (0..s.len() - 1)
                .min_by(|&a, &b| cost(s[a]).total_cmp(&cost(s[b])))
                .unwrap_or(0);
            if best != 0 && cost(s[best]) < cost(s[0]) {
                let s = &mut strokes[k];
                s.pop();
                s.rotate_left(best);
                s.push(s[0]);
            }
        }
    }
}

/// Draws consecutive strokes that meet exactly as one (no pen lift).
pub fn merge_touching(strokes: Vec<Stroke>) -> Vec<Stroke> {
    let mut out: Vec<Stroke> = Vec::with_capacity(strokes.len());
    for s in strokes {
        match out.last_mut() {
            Some(prev) if s.len() > 1 && prev.len() > 1 && prev.last() == s.first() => {
                prev.extend_from_slice(&s[1..])
            }
            _ => out.push(s),
        }
    }
    out
}

/// Orders and orients strokes without joining them.
pub fn order_strokes(strokes: &[Stroke], start: Pt, reverse: bool, effort: Effort) -> Vec<Stroke> {
    let ends: Vec<(Pt, Pt)> = strokes.iter().map(|s| (s[0], *s.last().unwrap())).collect();
    let p = order::Problem::new(&ends, start, reverse);
    let t = p.solve(effort);
    apply(strokes, &t)
}

/// The strokes in the tour's order and orientation.
pub fn apply(strokes: &[Stroke], t: &order::Tour) -> Vec<Stroke> {
    t.order
        .iter()
        .zip(&t.rev)
        .map(|(&i, &r)| {
            let mut s = strokes[i].clone();
            if r {
                s.reverse();
            }
            s
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loops_start_at_the_vertex_nearest_the_pen() {
        let square = vec![
            Pt::new(0.0, 0.0),
            Pt::new(1.0, 0.0),
            Pt::new(1.0, 1.0),
            Pt::new(0.0, 1.0),
            Pt::new(0.0, 0.0),
        ];
        let mut s = vec![square.clone()];
        rotate_loops(&mut s, Pt::new(2.0, 2.0));
        assert_eq!(s[0][0], Pt::new(1.0, 1.0));
        assert_eq!(s[0].last(), Some(&Pt::new(1.0, 1.0)));
        assert_eq!(s[0].len(), 5);
        // The direction of drawing is kept: (1,1) -> (0,1) as in the original.
        assert_eq!(s[0][1], Pt::new(0.0, 1.0));
        let planned = plan(&[square], Pt::new(2.0, 2.0), &PlanOptions::default());
        assert!((pen_up_travel(&planned, Pt::new(2.0, 2.0)) - 2f64.sqrt()).abs() < 1e-12);
    }
}
