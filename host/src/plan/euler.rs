//! Euler joining (the thesis, chapter 4.3): strokes whose end points meet are
//! edges of a graph; Hierholzer's algorithm walks each component so that
//! strokes meeting at junctions are drawn in one pen-down trail.
//!
//! A graph with 2k odd vertices cannot be drawn in one trail; like the
//! thesis we add k virtual edges between odd vertices (greedily paired by
//! distance) to make every degree even, walk the Euler circuit, and cut it
//! at the virtual edges, which leaves the minimum number of trails (k, or one
//! closed trail). The order of those trails is left to the ordering step.
//! Without reversal the same is done on the directed graph, balancing in- and
//! out-degree instead. End points closer than the tolerance count as equal;
//! where they are not exactly equal both points are kept, so no drawn
//! segment is lost or moved.

use super::near::Near;
use crate::geom::{Pt, Stroke};
use std::collections::HashMap;

/// Joins strokes at shared end points into as few trails as possible.
pub fn join(strokes: &[Stroke], tol: f64, reversible: bool) -> Vec<Stroke> {
    let mut nodes = NodeMap::new(tol);
    // edge e: (from node, to node, stroke index or None for virtual)
    let mut edges: Vec<(usize, usize, Option<usize>)> = Vec::new();
    // (smallest input index in the trail, trail): sorted at the end so that
    // unjoined strokes keep their input order (the planner's "natural").
    let mut out: Vec<(usize, Stroke)> = Vec::new();
    for (i, s) in strokes.iter().enumerate() {
        if s.len() < 2 {
            out.push((i, s.clone()));
            continue;
        }
        let u = nodes.id(s[0]);
        let v = nodes.id(*s.last().unwrap());
        edges.push((u, v, Some(i)));
    }
    let n = nodes.pts.len();
    // Degree balance: odd degree (undirected) or out - in (directed).
    let mut bal = vec![0i64; n];
    for &(u, v, _) in &edges {
        if reversible {
            bal[u] ^= 1;
            bal[v] ^= 1;
        } else {
            bal[u] += 1;
            bal[v] -= 1;
        }
    }
    // Virtual edges: undirected pairs odd vertices; directed runs from
    // vertices with surplus in-degree to those with surplus out-degree.
    let mut need_out: Vec<usize> = Vec::new(); // vertices a virtual edge leaves
    let mut need_in: Vec<usize> = Vec::new(); // vertices a virtual edge enters
    for (v, &b) in bal.iter().enumerate() {
        if reversible {
            if b != 0 {
                need_out.push(v);
            }
        } else {
            for _ in 0..(-b).max(0) {
                need_out.push(v);
            }
            for _ in 0..b.max(0) {
                need_in.push(v);
            }
        }
    }
    if reversible {
        pair_greedy_undirected(&nodes.pts, &mut need_out, &mut edges);
    } else {
        pair_greedy_directed(&nodes.pts, &need_out, &mut need_in, &mut edges);
    }
    // Adjacency: (edge, other end, traversed forward).
    let mut adj: Vec<Vec<(usize, usize, bool)>> = vec![Vec::new(); n];
    for (e, &(u, v, _)) in edges.iter().enumerate() {
        adj[u].push((e, v, true));
        if reversible {
            adj[v].push((e, u, false));
        }
    }
    let mut used = vec![false; edges.len()];
    let mut ptr = vec![0usize; n];
    for start in 0..n {
        loop {
            while ptr[start] < adj[start].len() && used[adj[start][ptr[start]].0] {
                ptr[start] += 1;
            }
            if ptr[start] == adj[start].len() {
                break;
            }
            let circuit = hierholzer(start, &adj, &mut used, &mut ptr);
            split_at_virtual(&circuit, &edges, strokes, &mut out);
        }
    }
    out.sort_by_key(|t| t.0);
    out.into_iter().map(|t| t.1).collect()
}

/// Iterative Hierholzer: the closed walk from `start` over unused edges.
fn hierholzer(
    start: usize,
    adj: &[Vec<(usize, usize, bool)>],
    used: &mut [bool],
    ptr: &mut [usize],
) -> Vec<(usize, bool)> {
    let mut stack: Vec<(usize, Option<(usize, bool)>)> = vec![(start, None)];
    let mut walk = Vec::new();
    while let Some(&(v, via)) = stack.last() {
        while ptr[v] < adj[v].len() && used[adj[v][ptr[v]].0] {
            ptr[v] += 1;
        }
        if ptr[v] == adj[v].len() {
            stack.pop();
            if let Some(e) = via {
                walk.push(e);
            }
        } else {
            let (e, w, fwd) = adj[v][ptr[v]];
            used[e] = true;
            stack.push((w, Some((e, fwd))));
        }
    }
    walk.reverse();
    walk
}

/// Cuts a closed walk at its virtual edges into pen-down trails.
fn split_at_virtual(
    walk: &[(usize, bool)],
    edges: &[(usize, usize, Option<usize>)],
    strokes: &[Stroke],
    out: &mut Vec<(usize, Stroke)>,
) {
    let first_virtual = walk.iter().position(|&(e, _)| edges[e].2.is_none());
    let rot = first_virtual.map_or(0, |k| k + 1);
    let mut trail: Stroke = Vec::new();
    let mut first = usize::MAX;
    for k in 0..walk.len() {
        let (e, fwd) = walk[(rot + k) % walk.len()];
        match edges[e].2 {
            None => {
                if !trail.is_empty() {
                    out.push((first, std::mem::take(&mut trail)));
                    first = usize::MAX;
                }
            }
            Some(i) => {
                first = first.min(i);
                let s = &strokes[i];
                let pts: Box<dyn Iterator<Item = &Pt>> = if fwd {
                    Box::new(s.iter())
                } else {
                    Box::new(s.iter().rev())
                };
                for (j, p) in pts.enumerate() {
                    if j == 0 && trail.last() == Some(p) {
                        continue;
                    }
                    trail.push(*p);
                }
            }
        }
    }
    if !trail.is_empty() {
        out.push((first, trail));
    }
}

/// Above this many candidates the greedy pairings use a grid, not a scan.
const SCAN_MAX: usize = 2000;

fn pair_greedy_undirected(
    pts: &[Pt],
    odd: &mut Vec<usize>,
    edges: &mut Vec<(usize, usize, Option<usize>)>,
) {
    if odd.len() > SCAN_MAX {
        // Same pairing rule (last odd vertex with its nearest), grid-searched.
        let mut near = Near::new(odd.iter().map(|&v| pts[v]).collect());
        for k in (0..odd.len()).rev() {
            if !near.is_live(k) {
                continue; // already some earlier vertex's nearest
            }
            near.remove(k);
            if let Some(j) = near.nearest(pts[odd[k]]) {
                near.remove(j);
                edges.push((odd[k], odd[j], None));
            }
        }
        odd.clear();
        return;
    }
    while let Some(u) = odd.pop() {
        let k = nearest(pts, u, odd);
        let v = odd.swap_remove(k);
        edges.push((u, v, None));
    }
}

/// Index in `cands` of the point nearest `pts[u]` (`usize::MAX` if `cands` is
/// empty; the first candidate when no distance compares, e.g. all infinite).
fn nearest(pts: &[Pt], u: usize, cands: &[usize]) -> usize {
    if cands.is_empty() {
        return usize::MAX;
    }
    cands
        .iter()
        .enumerate()
        .map(|(k, &v)| (k, pts[u].dist(pts[v])))
        .fold((0, f64::INFINITY), |b, c| if c.1 < b.1 { c } else { b })
        .0
}

fn pair_greedy_directed(
    pts: &[Pt],
    from: &[usize],
    to: &mut Vec<usize>,
    edges: &mut Vec<(usize, usize, Option<usize>)>,
) {
    if to.len() > SCAN_MAX {
        let mut near = Near::new(to.iter().map(|&v| pts[v]).collect());
        for &u in from {
            if let Some(k) = near.nearest(pts[u]) {
                near.remove(k);
                edges.push((u, to[k], None));
            }
        }
        to.clear();
        return;
    }
    for &u in from {
        let k = nearest(pts, u, to);
        let v = to.swap_remove(k);
        edges.push((u, v, None));
    }
}

/// Points snapped to nodes: a hash grid with cells of the tolerance.
struct NodeMap {
    tol: f64,
    grid: HashMap<(i64, i64), Vec<usize>>,
    pts: Vec<Pt>,
}

impl NodeMap {
    fn new(tol: f64) -> Self {
        NodeMap {
            tol: tol.max(1e-12),
            grid: HashMap::new(),
            pts: Vec::new(),
        }
    }

    fn cell(&self, p: Pt) -> (i64, i64) {
        (
            (p.x / self.tol).floor() as i64,
            (p.y / self.tol).floor() as i64,
        )
    }

    fn id(&mut self, p: Pt) -> usize {
        let (cx, cy) = self.cell(p);
        for dx in -1..=1i64 {
            for dy in -1..=1i64 {
                // Saturating: a far-off point's cell sits at the i64 limit.
                let c = (cx.saturating_add(dx), cy.saturating_add(dy));
                if let Some(ids) = self.grid.get(&c) {
                    if let Some(&i) = ids.iter().find(|&&i| self.pts[i].dist(p) <= self.tol) {
                        return i;
                    }
                }
            }
        }
        let i = self.pts.len();
        self.pts.push(p);
        self.grid.entry((cx, cy)).or_default().push(i);
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(pts: &[(f64, f64)]) -> Stroke {
        pts.iter().map(|&(x, y)| Pt::new(x, y)).collect()
    }

    #[test]
    fn square_with_diagonal_is_two_trails_at_most() {
        // A square plus one diagonal: two odd vertices, so one open trail.
        let strokes = vec![
            s(&[(0.0, 0.0), (1.0, 0.0)]),
            s(&[(1.0, 0.0), (1.0, 1.0)]),
            s(&[(1.0, 1.0), (0.0, 1.0)]),
            s(&[(0.0, 1.0), (0.0, 0.0)]),
            s(&[(0.0, 0.0), (1.0, 1.0)]),
        ];
        let out = join(&strokes, 1e-6, true);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].len(), 6);
        let ends = [out[0][0], *out[0].last().unwrap()];
        assert!(ends.contains(&Pt::new(0.0, 0.0)) && ends.contains(&Pt::new(1.0, 1.0)));
    }

    #[test]
    fn directed_join_respects_direction() {
        // a->b, b->c and c->b: drawable as a->b->c->b without reversal.
        let strokes = vec![
            s(&[(0.0, 0.0), (1.0, 0.0)]),
            s(&[(2.0, 0.0), (1.0, 0.0)]),
            s(&[(1.0, 0.0), (2.0, 0.0)]),
        ];
        let out = join(&strokes, 1e-6, false);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0], s(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (1.0, 0.0)]));
    }

    #[test]
    fn strokes_without_junctions_keep_their_order() {
        let strokes: Vec<Stroke> = (0..6)
            .map(|k| s(&[(k as f64 * 3.0, 0.0), (k as f64 * 3.0 + 1.0, 0.0)]))
            .rev()
            .collect();
        assert_eq!(join(&strokes, 1e-6, true), strokes);
        assert_eq!(join(&strokes, 1e-6, false), strokes);
    }
}
