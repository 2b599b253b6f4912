//! Geometry shared by every stage: points in millimetres (y up, like the
//! machine), strokes as polylines, the ends of the route a program drives (where
//! the pen starts and where it parks) and the pen-up travel over that whole
//! route, which the planner minimises and the G-code drives. Kept tiny and dependency-free
//! so the planner, the font loaders and the readers all speak the same types.

/// A point in the drawing plane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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

/// The ends of the pen-up route: where the pen is before the first stroke and
/// where the program leaves it after the last (None: where the last stroke ends).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Route {
    pub start: Pt,
    pub park: Option<Pt>,
}

impl Route {
    /// Starts and parks at `p`: a closed tour.
    pub const fn closed(p: Pt) -> Route {
        Route {
            start: p,
            park: Some(p),
        }
    }

    /// Starts at `p` and stays where the last stroke ends.
    pub const fn open(p: Pt) -> Route {
        Route {
            start: p,
            park: None,
        }
    }
}

/// Pen-up travel of the whole route: from the start through the strokes in the
/// given order, then to the park.
pub fn pen_up_travel(strokes: &[Stroke], route: Route) -> f64 {
    let mut at = route.start;
    let mut total = 0.0;
    for s in strokes {
        if let (Some(a), Some(b)) = (s.first(), s.last()) {
            total += at.dist(*a);
            at = *b;
        }
    }
    total + route.park.map_or(0.0, |p| at.dist(p))
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
        assert_eq!(pen_up_travel(&s, Route::open(Pt::new(0.0, 0.0))), 5.0 + 4.0);
        let park = Route {
            start: Pt::new(0.0, 0.0),
            park: Some(Pt::new(0.0, 3.0)),
        };
        assert_eq!(pen_up_travel(&s, park), 5.0 + 4.0 + 3.0);
        assert_eq!(pen_down_length(&s), 17.0);
        assert_eq!(bounds(&s), Some((Pt::new(0.0, 0.0), Pt::new(10.0, 4.0))));
    }
}
