//! Geometry shared by every stage: points in millimetres (y up, like the
//! machine), strokes as polylines, and the pen-up travel measure that the
//! planner minimises and the benchmark reports. Kept tiny and dependency-free
//! so the planner, the font loaders and the readers all speak the same types.

/// A point in the drawing plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pt {
    pub x: f64,
    pub y: f64,
}

impl Pt {
    pub const fn new(x: f64, y: f64) -> Self {
        Pt { x, y }
    }
    pub fn dist(self, o: Pt) -> f64 {
        (self.x - o.x).hypot(self.y - o.y)
    }
}

/// One pen-down stroke: the pen drops at the first point, draws through the
/// rest and lifts at the last. A stroke always has at least one point.
pub type Stroke = Vec<Pt>;

/// Pen-up travel from `start` through the strokes in the given order.
pub fn pen_up_travel(strokes: &[Stroke], start: Pt) -> f64 {
    let mut at = start;
    let mut total = 0.0;
    for s in strokes {
        if let (Some(a), Some(b)) = (s.first(), s.last()) {
            total += at.dist(*a);
            at = *b;
        }
    }
    total
}

/// Pen-down length of all strokes.
pub fn pen_down_length(strokes: &[Stroke]) -> f64 {
    strokes
        .iter()
        .map(|s| s.windows(2).map(|w| w[0].dist(w[1])).sum::<f64>())
        .sum()
}

/// Bounding box (min, max) of all points, or None when there are none.
pub fn bounds(strokes: &[Stroke]) -> Option<(Pt, Pt)> {
    let mut it = strokes.iter().flatten();
    let first = *it.next()?;
    let (mut lo, mut hi) = (first, first);
    for p in it {
        lo.x = lo.x.min(p.x);
        lo.y = lo.y.min(p.y);
        hi.x = hi.x.max(p.x);
        hi.y = hi.y.max(p.y);
    }
    Some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn travel_counts_start_and_gaps() {
        let s = vec![
            vec![Pt::new(3.0, 4.0), Pt::new(10.0, 4.0)],
            vec![Pt::new(10.0, 0.0), Pt::new(0.0, 0.0)],
        ];
        assert_eq!(pen_up_travel(&s, Pt::new(0.0, 0.0)), 5.0 + 4.0);
        assert_eq!(pen_down_length(&s), 17.0);
        assert_eq!(bounds(&s), Some((Pt::new(0.0, 0.0), Pt::new(10.0, 4.0))));
    }
}
