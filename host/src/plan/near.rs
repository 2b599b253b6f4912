//! Nearest live point queries for the greedy steps of planning (nearest
//! free stroke end, nearest odd vertex): a uniform grid of about two points
//! per cell, searched in rings around the query until no closer point can
//! lie further out. Points are removed as they are used; when few are left
//! the grid is rebuilt coarser, so a query never scans a sea of empty cells.
//! This keeps the greedy tour of 179,000 strokes at O(n) queries of small
//! cost, where the scan of every free end was O(n^2).

use crate::geom::Pt;

pub struct Near {
    pts: Vec<Pt>,
    alive: Vec<bool>,
    live: usize,
    lo: Pt,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl Near {
    /// A grid over `pts` (all live). Non-finite points are never found.
    pub fn new(pts: Vec<Pt>) -> Near {
        let alive: Vec<bool> = pts
            .iter()
            .map(|p| p.x.is_finite() && p.y.is_finite())
            .collect();
        let live = alive.iter().filter(|&&a| a).count();
        let mut n = Near {
            pts,
            alive,
            live,
            lo: Pt::new(0.0, 0.0),
            cell: 1.0,
            nx: 1,
            ny: 1,
            cells: Vec::new(),
        };
        n.rebuild();
        n
    }

    fn rebuild(&mut self) {
        let live = || {
            self.pts
                .iter()
                .zip(&self.alive)
                .filter(|(_, &a)| a)
                .map(|(p, _)| *p)
        };
        let (mut lo, mut hi) = (Pt::new(f64::MAX, f64::MAX), Pt::new(f64::MIN, f64::MIN));
        for p in live() {
            lo = Pt::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Pt::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        if self.live == 0 {
            self.cells = vec![Vec::new()];
            self.nx = 1;
            self.ny = 1;
            return;
        }
        let (w, h) = ((hi.x - lo.x).max(1e-9), (hi.y - lo.y).max(1e-9));
        let target = (self.live as f64 / 2.0).max(1.0);
        let mut cell = (w * h / target).sqrt().max(1e-9);
        // Keep the grid within a sane number of cells whatever the shape.
        while (w / cell).ceil() * (h / cell).ceil() > 4.0 * target + 16.0 {
            cell *= 1.5;
        }
        self.lo = lo;
        self.cell = cell;
        self.nx = ((w / cell).floor() as usize + 1).max(1);
        self.ny = ((h / cell).floor() as usize + 1).max(1);
        self.cells = vec![Vec::new(); self.nx * self.ny];
        for i in 0..self.pts.len() {
            if self.alive[i] {
                let c = self.cell_of(self.pts[i]);
                self.cells[c.1 * self.nx + c.0].push(i as u32);
            }
        }
    }

    fn cell_of(&self, p: Pt) -> (usize, usize) {
        let cx = ((p.x - self.lo.x) / self.cell).floor();
        let cy = ((p.y - self.lo.y) / self.cell).floor();
        (
            (cx.max(0.0) as usize).min(self.nx - 1),
            (cy.max(0.0) as usize).min(self.ny - 1),
        )
    }

    pub fn live(&self) -> usize {
        self.live
    }

    pub fn is_live(&self, i: usize) -> bool {
        self.alive.get(i).copied().unwrap_or(false)
    }

    /// Removes point `i` (no effect if already gone).
    pub fn remove(&mut self, i: usize) {
        if !self.alive.get(i).copied().unwrap_or(false) {
            return;
        }
        self.alive[i] = false;
        self.live -= 1;
        let c = self.cell_of(self.pts[i]);
        let v = &mut self.cells[c.1 * self.nx + c.0];
        if let Some(k) = v.iter().position(|&j| j as usize == i) {
            v.swap_remove(k);
        }
        if self.live > 0 && self.live * 8 < self.cells.len() && self.cells.len() > 64 {
            self.rebuild();
        }
    }

    /// The live point nearest `q` (ties: any), or None when none is left.
    pub fn nearest(&self, q: Pt) -> Option<usize> {
        if self.live == 0 {
            return None;
        }
        // The query's cell, clamped onto the grid.
        let fx = (q.x - self.lo.x) / self.cell;
        let fy = (q.y - self.lo.y) / self.cell;
        let cx = (fx.max(0.0).min((self.nx - 1) as f64)) as i64;
        let cy = (fy.max(0.0).min((self.ny - 1) as f64)) as i64;
        let qc = Pt::new(
            q.x.clamp(self.lo.x, self.lo.x + self.nx as f64 * self.cell),
            q.y.clamp(self.lo.y, self.lo.y + self.ny as f64 * self.cell),
        );
        let out2 = q.dist(qc).powi(2);
        let mut best: Option<(f64, usize)> = None;
        let rmax = self.nx.max(self.ny) as i64;
        for r in 0..=rmax {
            // q' (q clamped onto the grid) lies in the centre cell, so a point
            // in ring r is at least (r - 1) cells from q'; and as q' is q's
            // projection onto the grid's rectangle, |q - p|^2 >= |q - q'|^2 +
            // |q' - p|^2.
            if let Some((d, _)) = best {
                let ring = (r as f64 - 1.0).max(0.0) * self.cell;
                if out2 + ring * ring > d * d {
                    break;
                }
            }
            let (x0, x1, y0, y1) = (cx - r, cx + r, cy - r, cy + r);
            for y in y0.max(0)..=y1.min(self.ny as i64 - 1) {
                let on_edge_row = y == y0 || y == y1;
                let mut x = x0.max(0);
                while x <= x1.min(self.nx as i64 - 1) {
                    for &i in &self.cells[y as usize * self.nx + x as usize] {
                        let d = q.dist(self.pts[i as usize]);
                        if best.is_none_or(|b| d < b.0) {
                            best = Some((d, i as usize));
                        }
                    }
                    x = if on_edge_row || x == x1 { x + 1 } else { x1 };
                }
            }
        }
        best.map(|b| b.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_what_a_scan_finds_while_points_go() {
        let mut s = 0x2545_F491_4F6C_DD1Du64;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 100_000) as f64 / 100.0
        };
        // Clustered and spread points.
        let pts: Vec<Pt> = (0..3000)
            .map(|k| {
                if k % 3 == 0 {
                    Pt::new(rnd() / 100.0, rnd() / 100.0)
                } else {
                    Pt::new(rnd(), rnd() * 0.1)
                }
            })
            .collect();
        let mut n = Near::new(pts.clone());
        let mut alive = vec![true; pts.len()];
        for step in 0..3000 {
            let q = Pt::new(rnd() * 1.5 - 200.0, rnd() - 10.0);
            let got = n.nearest(q).unwrap();
            let want = (0..pts.len())
                .filter(|&i| alive[i])
                .map(|i| q.dist(pts[i]))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(q.dist(pts[got]), want, "step {step}");
            n.remove(got);
            alive[got] = false;
        }
        assert_eq!(n.nearest(Pt::new(0.0, 0.0)), None);
    }
}
