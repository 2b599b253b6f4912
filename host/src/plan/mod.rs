//! Pen-path planning: the one entry point that turns strokes in any order
//! into strokes in drawing order, for the whole route the program drives: from
//! the pen's start, through every stroke, to where the pen parks. Euler joining
//! first (strokes meeting at junctions become single trails), then ordering and
//! orientation. The result is never worse than the strokes as given: if the
//! search loses to the natural order (it cannot, but the guard makes it a
//! guarantee), the natural order is returned. Closed strokes are then rotated to
//! start at their best vertex, and strokes that meet exactly are drawn as one.

pub mod euler;
pub mod near;
pub mod order;

use crate::geom::{pen_up_travel, Pt, Route, Stroke};
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
    /// Report the stages of large plans (over 5,000 strokes) on stderr.
    pub progress: bool,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            reverse: true,
            join: true,
            join_tol: 1e-3,
            effort: Effort::default(),
            progress: false,
        }
    }
}

/// Orders (and orients, joins) strokes to reduce the pen-up travel of the route.
///
/// Time is bounded: joining and the greedy tour are near-linear (grid
/// searches), and the local search stops at `effort.time_limit`, so a drawing
/// of 179,000 strokes plans in seconds.
pub fn plan(strokes: &[Stroke], route: Route, opt: &PlanOptions) -> Vec<Stroke> {
    let t0 = std::time::Instant::now();
    let say = |what: &str| {
        if opt.progress && strokes.len() > 5000 {
            eprintln!(
                "planning {} strokes: {what} ({:.1} s)",
                strokes.len(),
                t0.elapsed().as_secs_f64()
            );
        }
    };
    // Strokes with points that are not finite cannot be measured: they are
    // kept, unplanned, at the end (the G-code writer refuses them anyway).
    let finite = |s: &&Stroke| s.iter().all(|p| p.x.is_finite() && p.y.is_finite());
    let odd: Vec<Stroke> = strokes.iter().filter(|s| !finite(s)).cloned().collect();
    if !odd.is_empty() {
        let good: Vec<Stroke> = strokes.iter().filter(finite).cloned().collect();
        let mut p = plan(&good, route, opt);
        p.extend(odd);
        return p;
    }
    let strokes: Vec<Stroke> = strokes.iter().filter(|s| !s.is_empty()).cloned().collect();
    let joined = if opt.join {
        let j = euler::join(&strokes, opt.join_tol, opt.reverse);
        say(&format!("joined into {} trails", j.len()));
        j
    } else {
        strokes.clone()
    };
    say(&format!(
        "ordering; local search for at most {:.0} s",
        opt.effort.time_limit.as_secs_f64()
    ));
    let mut planned = order_strokes(&joined, route, opt.reverse, opt.effort);
    say("ordered");
    rotate_loops(&mut planned, route);
    if opt.join {
        planned = merge_touching(planned);
    }
    if pen_up_travel(&planned, route) <= pen_up_travel(&strokes, route) {
        planned
    } else {
        strokes
    }
}

/// A closed stroke (first point == last) can be drawn from any of its
/// vertices: start each one at the vertex nearest to the pen coming in and
/// the next stroke (or the park) going out. Each change lowers the travel, so
/// this only improves; two passes let neighbouring loops settle.
pub fn rotate_loops(strokes: &mut [Stroke], route: Route) {
    for _ in 0..2 {
        for k in 0..strokes.len() {
            let s = &strokes[k];
            if s.len() < 3 || s.first() != s.last() {
                continue;
            }
            let before = if k == 0 {
                route.start
            } else {
                *strokes[k - 1].last().unwrap()
            };
            let after = strokes.get(k + 1).map(|n| n[0]).or(route.park);
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
pub fn order_strokes(
    strokes: &[Stroke],
    route: Route,
    reverse: bool,
    effort: Effort,
) -> Vec<Stroke> {
    let ends: Vec<(Pt, Pt)> = strokes.iter().map(|s| (s[0], *s.last().unwrap())).collect();
    let p = order::Problem::new(&ends, route, reverse);
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
        rotate_loops(&mut s, Route::open(Pt::new(2.0, 2.0)));
        assert_eq!(s[0][0], Pt::new(1.0, 1.0));
        assert_eq!(s[0].last(), Some(&Pt::new(1.0, 1.0)));
        assert_eq!(s[0].len(), 5);
        // The direction of drawing is kept: (1,1) -> (0,1) as in the original.
        assert_eq!(s[0][1], Pt::new(0.0, 1.0));
        let route = Route::open(Pt::new(2.0, 2.0));
        let planned = plan(
            std::slice::from_ref(&square),
            route,
            &PlanOptions::default(),
        );
        assert!((pen_up_travel(&planned, route) - 2f64.sqrt()).abs() < 1e-12);
        // With a park, the loop starts (and ends) at the corner that minimises
        // the way in plus the way out: (0,1), sqrt(5) + 1 (not (1,1), sqrt(2) + 2).
        let route = Route {
            start: Pt::new(2.0, 2.0),
            park: Some(Pt::new(-1.0, 1.0)),
        };
        let planned = plan(&[square], route, &PlanOptions::default());
        assert_eq!(planned[0][0], Pt::new(0.0, 1.0));
        assert!((pen_up_travel(&planned, route) - (5f64.sqrt() + 1.0)).abs() < 1e-12);
    }

    #[test]
    fn the_park_is_part_of_the_route() {
        // Three dots. Open, the best route from the origin is P, R, Q (1 + 6.40 +
        // 7.07); back home it is P, Q, R (1 + 9 + 7.07 + 7.07), which the open
        // plan misses by 0.33.
        let (p, q, r) = (Pt::new(1.0, 0.0), Pt::new(10.0, 0.0), Pt::new(5.0, 5.0));
        let strokes = vec![vec![r], vec![q], vec![p]];
        let open = Route::open(Pt::new(0.0, 0.0));
        let closed = Route::closed(Pt::new(0.0, 0.0));
        let p_open = plan(&strokes, open, &PlanOptions::default());
        let p_closed = plan(&strokes, closed, &PlanOptions::default());
        assert_eq!(p_open, vec![vec![p], vec![r], vec![q]]);
        assert!(
            p_closed == vec![vec![p], vec![q], vec![r]]
                || p_closed == vec![vec![r], vec![q], vec![p]]
        );
        let best = 1.0 + 9.0 + 2.0 * 50f64.sqrt();
        assert!((pen_up_travel(&p_closed, closed) - best).abs() < 1e-12);
        assert!(pen_up_travel(&p_open, closed) > best + 0.3);
    }
}
