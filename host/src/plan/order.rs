//! Stroke ordering: choose the order (and, when allowed, the direction) in
//! which strokes are drawn so that the pen-up travel of the whole route, from the
//! pen's start to where it parks, is small.
//!
//! This is an asymmetric-endpoint TSP with fixed ends: a path from the start to
//! the park, a closed tour when they are the same point, or an open path when the
//! pen stays where the last stroke ends. Every move below prices the step to the
//! park like any other gap, so the whole route is what gets optimised. The strategy, measured on the
//! benchmark text: a greedy nearest-endpoint tour and the natural order both
//! go through the same local search (2-opt with stroke reversal, or-opt moves
//! of chains of 1-3 strokes, and an exact DP over subsets with orientation on
//! every window of up to 9 consecutive strokes), then an iterated local search
//! with double-bridge kicks; the best tour wins. Local search never increases
//! the cost, so the result is never worse than the natural order. A seeded
//! generator keeps the result reproducible.

use crate::geom::{Pt, Route};
use std::time::{Duration, Instant};

const EPS: f64 = 1e-9;

/// Stroke end points and the ends of the route: all ordering needs to know.
pub struct Problem {
    /// End points: 2i is stroke i's start, 2i + 1 its end, 2n the pen start,
    /// 2n + 1 the park if there is one.
    pts: Vec<Pt>,
    /// Number of strokes.
    n: usize,
    park: bool,
    /// Full distance matrix over `pts` when it is small enough to keep.
    dm: Option<Vec<f64>>,
    reversible: bool,
}

/// Largest stroke count for which the distance matrix is kept (~16 MB).
const MATRIX_MAX: usize = 700;

type Id = usize;

/// A tour: stroke indices in drawing order, and whether each is drawn reversed.
#[derive(Clone, Debug, PartialEq)]
pub struct Tour {
    pub order: Vec<usize>,
    pub rev: Vec<bool>,
}

/// How hard to search.
#[derive(Clone, Copy, Debug)]
pub struct Effort {
    /// Iterated-local-search kicks after the first local optimum.
    pub kicks: usize,
    /// Wall-clock limit for everything after the greedy tour.
    pub time_limit: Duration,
    /// Largest window for the exact subset DP (<= 12).
    pub window: usize,
}

impl Default for Effort {
    fn default() -> Self {
        Effort {
            kicks: 200,
            time_limit: Duration::from_secs(3),
            window: 9,
        }
    }
}

impl Problem {
    pub fn new(ends: &[(Pt, Pt)], route: Route, reversible: bool) -> Self {
        let mut pts: Vec<Pt> = ends.iter().flat_map(|e| [e.0, e.1]).collect();
        pts.push(route.start);
        pts.extend(route.park);
        let dm = (ends.len() <= MATRIX_MAX).then(|| {
            pts.iter()
                .flat_map(|a| pts.iter().map(move |b| a.dist(*b)))
                .collect()
        });
        Problem {
            pts,
            n: ends.len(),
            park: route.park.is_some(),
            dm,
            reversible,
        }
    }

    pub fn len(&self) -> usize {
        self.n
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn start(&self) -> Id {
        2 * self.n
    }

    fn park(&self) -> Option<Id> {
        self.park.then_some(2 * self.n + 1)
    }

    #[inline]
    fn d(&self, u: Id, v: Id) -> f64 {
        match &self.dm {
            Some(m) => m[u * self.pts.len() + v],
            None => self.pts[u].dist(self.pts[v]),
        }
    }

    fn entry(&self, i: usize, r: bool) -> Id {
        2 * i + r as usize
    }

    fn exit(&self, i: usize, r: bool) -> Id {
        2 * i + !r as usize
    }

    pub fn natural(&self) -> Tour {
        Tour {
            order: (0..self.len()).collect(),
            rev: vec![false; self.len()],
        }
    }

    pub fn cost(&self, t: &Tour) -> f64 {
        let mut at = self.start();
        let mut c = 0.0;
        for (k, &i) in t.order.iter().enumerate() {
            c += self.d(at, self.entry(i, t.rev[k]));
            at = self.exit(i, t.rev[k]);
        }
        c + self.park().map_or(0.0, |p| self.d(at, p))
    }

    /// Nearest free end point next, from the start.
    pub fn greedy(&self) -> Tour {
        if self.len() > MATRIX_MAX {
            return self.greedy_grid();
        }
        let n = self.len();
        let mut free = vec![true; n];
        let mut t = Tour {
            order: Vec::with_capacity(n),
            rev: Vec::with_capacity(n),
        };
        let mut at = self.start();
        for _ in 0..n {
            // Any free stroke first (distances may all be infinite).
            let any = (0..n).find(|&i| free[i]).unwrap_or(0);
            let mut best = (f64::INFINITY, any, false);
            for i in (0..n).filter(|&i| free[i]) {
                let d = self.d(at, 2 * i);
                if d < best.0 {
                    best = (d, i, false);
                }
                if self.reversible {
                    let d = self.d(at, 2 * i + 1);
                    if d < best.0 {
                        best = (d, i, true);
                    }
                }
            }
            free[best.1] = false;
            t.order.push(best.1);
            t.rev.push(best.2);
            at = self.exit(best.1, best.2);
        }
        t
    }

    /// [`Problem::greedy`] with a grid for the nearest end: O(n) small
    /// queries instead of a scan of every free end per step.
    fn greedy_grid(&self) -> Tour {
        let n = self.len();
        let mut near = super::near::Near::new(self.pts[..2 * n].to_vec());
        if !self.reversible {
            for i in 0..n {
                near.remove(2 * i + 1);
            }
        }
        let mut t = Tour {
            order: Vec::with_capacity(n),
            rev: Vec::with_capacity(n),
        };
        let mut at = self.pts[self.start()];
        let mut free = vec![true; n];
        while let Some(id) = near.nearest(at) {
            let (i, r) = (id / 2, id % 2 == 1);
            near.remove(2 * i);
            near.remove(2 * i + 1);
            free[i] = false;
            t.order.push(i);
            t.rev.push(r);
            at = self.pts[self.exit(i, r)];
        }
        // Strokes with end points the grid cannot hold (not finite) go last.
        for i in (0..n).filter(|&i| free[i]) {
            t.order.push(i);
            t.rev.push(false);
        }
        t
    }

    /// The best tour found within the effort: local search from the natural
    /// and the greedy tours, then iterated local search from the better one.
    pub fn solve(&self, effort: Effort) -> Tour {
        let deadline = Instant::now() + effort.time_limit;
        let mut best = self.greedy();
        self.local_search(&mut best, effort.window, deadline);
        // The natural order as a second start (small sets; for large ones it
        // would eat the time budget) or at least as a floor.
        let mut nat = self.natural();
        if self.len() <= MATRIX_MAX {
            self.local_search(&mut nat, effort.window, deadline);
        }
        if self.cost(&nat) < self.cost(&best) {
            best = nat;
        }
        let mut best_cost = self.cost(&best);
        let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
        if self.len() >= 8 {
            for _ in 0..effort.kicks {
                if Instant::now() >= deadline {
                    break;
                }
                let mut t = best.clone();
                double_bridge(&mut t, &mut rng);
                self.local_search(&mut t, 0, deadline);
                let c = self.cost(&t);
                if c < best_cost - EPS {
                    self.local_search(&mut t, effort.window, deadline);
                    best_cost = self.cost(&t);
                    best = t;
                }
            }
        }
        best
    }

    /// Repeats 2-opt, or-opt and (if `window` > 1) the windowed exact DP
    /// until none improves or the deadline passes.
    pub fn local_search(&self, t: &mut Tour, window: usize, deadline: Instant) {
        loop {
            let mut improved = false;
            while Instant::now() < deadline
                && (self.two_opt(t, deadline) | self.or_opt(t, deadline))
            {
                improved = true;
            }
            if window > 1 && Instant::now() < deadline && self.window_dp(t, window, deadline) {
                improved = true;
            }
            if !improved || Instant::now() >= deadline {
                return;
            }
        }
    }

    fn ent(&self, t: &Tour, k: usize) -> Id {
        self.entry(t.order[k], t.rev[k])
    }

    fn ext(&self, t: &Tour, k: usize) -> Id {
        self.exit(t.order[k], t.rev[k])
    }

    fn before(&self, t: &Tour, k: usize) -> Id {
        if k == 0 {
            self.start()
        } else {
            self.ext(t, k - 1)
        }
    }

    /// Where the pen goes after the gap before position `k`: stroke k's entry, or
    /// the park past the last stroke (None for an open route).
    fn after(&self, t: &Tour, k: usize) -> Option<Id> {
        if k < t.order.len() {
            Some(self.ent(t, k))
        } else {
            self.park()
        }
    }

    /// One first-improvement pass of segment reversal (which also reverses
    /// every stroke inside; j == i is a single flip). Needs reversible strokes.
    pub fn two_opt(&self, t: &mut Tour, deadline: Instant) -> bool {
        if !self.reversible {
            return false;
        }
        let n = t.order.len();
        let mut improved = false;
        for i in 0..n {
            if i % 64 == 0 && Instant::now() >= deadline {
                break;
            }
            let p = self.before(t, i);
            let ei = self.ent(t, i);
            let d_pi = self.d(p, ei);
            for j in i..n {
                let xj = self.ext(t, j);
                let mut delta = self.d(p, xj) - d_pi;
                if let Some(q) = self.after(t, j + 1) {
                    delta += self.d(ei, q) - self.d(xj, q);
                }
                if delta < -EPS {
                    t.order[i..=j].reverse();
                    t.rev[i..=j].reverse();
                    for r in &mut t.rev[i..=j] {
                        *r = !*r;
                    }
                    improved = true;
                    break;
                }
            }
        }
        improved
    }

    /// One first-improvement pass moving chains of 1..=3 strokes elsewhere,
    /// reversed too when strokes are reversible.
    pub fn or_opt(&self, t: &mut Tour, deadline: Instant) -> bool {
        let n = t.order.len();
        let mut improved = false;
        for len in 1..=3usize {
            let mut i = 0;
            while i + len <= n {
                if i % 64 == 0 && Instant::now() >= deadline {
                    return improved;
                }
                if let Some((g, rev)) = self.best_insertion(t, i, len) {
                    let mut seg_o: Vec<usize> = t.order.drain(i..i + len).collect();
                    let mut seg_r: Vec<bool> = t.rev.drain(i..i + len).collect();
                    if rev {
                        seg_o.reverse();
                        seg_r.reverse();
                        for r in &mut seg_r {
                            *r = !*r;
                        }
                    }
                    let at = if g < i { g } else { g - len };
                    t.order.splice(at..at, seg_o);
                    t.rev.splice(at..at, seg_r);
                    improved = true;
                }
                i += 1;
            }
        }
        improved
    }

    /// The improving gap (and orientation) for the chain t[i..i+len], if any.
    fn best_insertion(&self, t: &Tour, i: usize, len: usize) -> Option<(usize, bool)> {
        let n = t.order.len();
        let e = i + len - 1;
        let p = self.before(t, i);
        let (si, se) = (self.ent(t, i), self.ext(t, e));
        let next = self.after(t, e + 1);
        let gain = self.d(p, si) + next.map_or(0.0, |q| self.d(se, q) - self.d(p, q));
        let mut best: Option<(f64, usize, bool)> = None;
        for g in (0..=n).filter(|&g| g < i || g > i + len) {
            let x = self.before(t, g);
            let y = self.after(t, g);
            let base = y.map_or(0.0, |y| self.d(x, y));
            let fwd = self.d(x, si) + y.map_or(0.0, |y| self.d(se, y)) - base;
            let mut cand = (fwd, false);
            if self.reversible {
                let bwd = self.d(x, se) + y.map_or(0.0, |y| self.d(si, y)) - base;
                if bwd < fwd {
                    cand = (bwd, true);
                }
            }
            let delta = cand.0 - gain;
            if delta < -EPS && best.is_none_or(|b| delta < b.0) {
                best = Some((delta, g, cand.1));
            }
        }
        best.map(|b| (b.1, b.2))
    }

    /// Exact re-ordering of every window of `w` consecutive strokes, with the
    /// stroke before and after the window fixed: DP over subsets x last
    /// stroke x orientation. Returns whether any window improved.
    pub fn window_dp(&self, t: &mut Tour, w: usize, deadline: Instant) -> bool {
        let n = t.order.len();
        let w = w.min(n).min(12);
        if w < 2 {
            return false;
        }
        let mut improved = false;
        for s in 0..=n - w {
            if Instant::now() >= deadline {
                break;
            }
            improved |= self.solve_window(t, s, w);
        }
        improved
    }

    fn solve_window(&self, t: &mut Tour, s: usize, w: usize) -> bool {
        let p = self.before(t, s);
        let q = self.after(t, s + w);
        let items: Vec<usize> = t.order[s..s + w].to_vec();
        let fixed: Vec<bool> = t.rev[s..s + w].to_vec();
        let o_of = |k: usize, o: usize| if self.reversible { o == 1 } else { fixed[k] };
        let no = if self.reversible { 2 } else { 1 };
        let full = (1usize << w) - 1;
        let idx = |m: usize, k: usize, o: usize| (m * w + k) * no + o;
        // Distances between every exit and every entry in the window, once.
        let ks = w * no;
        let mut d = vec![0.0; ks * ks];
        for a in 0..ks {
            let x = self.exit(items[a / no], o_of(a / no, a % no));
            for b in 0..ks {
                d[a * ks + b] = self.d(x, self.entry(items[b / no], o_of(b / no, b % no)));
            }
        }
        let mut dp = vec![f64::INFINITY; (full + 1) * ks];
        let mut par = vec![u16::MAX; (full + 1) * ks];
        for k in 0..w {
            for o in 0..no {
                dp[idx(1 << k, k, o)] = self.d(p, self.entry(items[k], o_of(k, o)));
            }
        }
        for m in 1..=full {
            for a in 0..ks {
                let k = a / no;
                let v = dp[m * ks + a];
                if m & (1 << k) == 0 || !v.is_finite() {
                    continue;
                }
                let row = &d[a * ks..(a + 1) * ks];
                for (b, &dab) in row.iter().enumerate() {
                    let k2 = b / no;
                    if m & (1 << k2) != 0 {
                        continue;
                    }
                    let j = (m | (1 << k2)) * ks + b;
                    let c = v + dab;
                    if c < dp[j] {
                        dp[j] = c;
                        par[j] = a as u16;
                    }
                }
            }
        }
        let tail =
            |k: usize, o: usize| q.map_or(0.0, |q| self.d(self.exit(items[k], o_of(k, o)), q));
        let mut best = (f64::INFINITY, 0, 0);
        for k in 0..w {
            for o in 0..no {
                let c = dp[idx(full, k, o)] + tail(k, o);
                if c < best.0 {
                    best = (c, k, o);
                }
            }
        }
        let mut current = self.d(p, self.ent(t, s));
        for k in s..s + w - 1 {
            current += self.d(self.ext(t, k), self.ent(t, k + 1));
        }
        current += q.map_or(0.0, |q| self.d(self.ext(t, s + w - 1), q));
        if best.0 >= current - EPS {
            return false;
        }
        let (mut m, mut k, mut o) = (full, best.1, best.2);
        for pos in (s..s + w).rev() {
            t.order[pos] = items[k];
            t.rev[pos] = o_of(k, o);
            let pr = par[idx(m, k, o)];
            m &= !(1 << k);
            if pr != u16::MAX {
                k = pr as usize / no;
                o = pr as usize % no;
            }
        }
        true
    }
}

/// Reorders A B C D into A C B D at three random cut points.
fn double_bridge(t: &mut Tour, rng: &mut XorShift) {
    let n = t.order.len();
    let mut cuts = [
        1 + rng.below(n - 1),
        1 + rng.below(n - 1),
        1 + rng.below(n - 1),
    ];
    cuts.sort_unstable();
    let [c1, c2, c3] = cuts;
    if c1 == c2 || c2 == c3 {
        return;
    }
    bridge(&mut t.order, c1, c2, c3);
    bridge(&mut t.rev, c1, c2, c3);
}

fn bridge<T: Copy>(v: &mut Vec<T>, c1: usize, c2: usize, c3: usize) {
    let mut out = Vec::with_capacity(v.len());
    out.extend_from_slice(&v[..c1]);
    out.extend_from_slice(&v[c2..c3]);
    out.extend_from_slice(&v[c1..c2]);
    out.extend_from_slice(&v[c3..]);
    *v = out;
}

/// A small deterministic generator (xorshift64*): reproducible plans.
struct XorShift(u64);

impl XorShift {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 33) as usize % n.max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(x0: f64, y0: f64, x1: f64, y1: f64) -> (Pt, Pt) {
        (Pt::new(x0, y0), Pt::new(x1, y1))
    }

    #[test]
    fn reversal_finds_the_zero_gap_tour() {
        // Three collinear segments given out of order and backwards.
        let p = Problem::new(
            &[
                seg(3.0, 0.0, 2.0, 0.0),
                seg(0.0, 0.0, 1.0, 0.0),
                seg(5.0, 0.0, 4.0, 0.0),
            ],
            Route::open(Pt::new(0.0, 0.0)),
            true,
        );
        let t = p.solve(Effort::default());
        assert_eq!(t.order, vec![1, 0, 2]);
        assert_eq!(t.rev, vec![false, true, true]);
        assert!((p.cost(&t) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn keeps_direction_when_not_reversible() {
        let p = Problem::new(
            &[seg(1.0, 0.0, 0.0, 0.0), seg(2.0, 0.0, 3.0, 0.0)],
            Route::open(Pt::new(0.0, 0.0)),
            false,
        );
        let t = p.solve(Effort::default());
        assert!(t.rev.iter().all(|r| !r));
        // 0 -> (1,0) draw to 0 -> (2,0): 1 + 2 = 3; other order: 2 + 2 = 4.
        assert!((p.cost(&t) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn window_dp_matches_brute_force() {
        let mut rng = XorShift(12345);
        let mut r = || rng.below(1000) as f64 / 10.0;
        let ends: Vec<_> = (0..6).map(|_| seg(r(), r(), r(), r())).collect();
        let p = Problem::new(&ends, Route::closed(Pt::new(0.0, 0.0)), true);
        let mut t = p.natural();
        p.window_dp(&mut t, 6, Instant::now() + Duration::from_secs(60));
        // Brute force over all orders and orientations.
        let mut best = f64::INFINITY;
        let mut perm: Vec<usize> = (0..6).collect();
        permute(&mut perm, 0, &mut |o| {
            for mask in 0..64u32 {
                let rev = (0..6).map(|k| mask & (1 << k) != 0).collect();
                best = best.min(p.cost(&Tour {
                    order: o.to_vec(),
                    rev,
                }));
            }
        });
        assert!(
            (p.cost(&t) - best).abs() < 1e-9,
            "{} vs {}",
            p.cost(&t),
            best
        );
    }

    #[test]
    fn directed_window_dp_matches_brute_force() {
        let mut rng = XorShift(777);
        let mut r = || rng.below(1000) as f64 / 10.0;
        let ends: Vec<_> = (0..7).map(|_| seg(r(), r(), r(), r())).collect();
        let p = Problem::new(
            &ends,
            Route {
                start: Pt::new(0.0, 0.0),
                park: Some(Pt::new(50.0, 50.0)),
            },
            false,
        );
        let mut t = p.natural();
        p.window_dp(&mut t, 7, Instant::now() + Duration::from_secs(60));
        let mut best = f64::INFINITY;
        let mut perm: Vec<usize> = (0..7).collect();
        permute(&mut perm, 0, &mut |o| {
            best = best.min(p.cost(&Tour {
                order: o.to_vec(),
                rev: vec![false; 7],
            }));
        });
        assert!(t.rev.iter().all(|r| !r));
        assert!(
            (p.cost(&t) - best).abs() < 1e-9,
            "{} vs {}",
            p.cost(&t),
            best
        );
    }

    fn permute(v: &mut Vec<usize>, k: usize, f: &mut dyn FnMut(&[usize])) {
        if k == v.len() {
            f(v);
            return;
        }
        for i in k..v.len() {
            v.swap(k, i);
            permute(v, k + 1, f);
            v.swap(k, i);
        }
    }
}
