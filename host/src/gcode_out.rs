//! Strokes to G-code, in the plain Grbl dialect the firmware and the
//! simulator accept: G21 G90, pen-up travel as G0, pen-down strokes as G1
//! with F, and the pen lifted and dropped either by M5/M3 (the firmware maps
//! them to the servo or Z, as its settings say) or by moving Z explicitly.
//! The program ends by parking the pen where the route says (a G0 there).
//! Lines stay short (well under Grbl's 80-character line buffer).

use crate::geom::{pen_down_length, pen_up_travel, Pt, Route, Stroke};
use std::fmt::Write as _;

/// How the pen is lifted and dropped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pen {
    /// M3 drops the pen, M5 lifts it.
    M3,
    /// Z moves: `up` and `down` heights (mm), Z moved at `feed` mm/min.
    Z { up: f64, down: f64, feed: f64 },
}

#[derive(Clone, Copy, Debug)]
pub struct GcodeOptions {
    pub pen: Pen,
    /// Drawing feed (mm/min).
    pub feed: f64,
    /// Dwell after each pen move (s), 0 for none.
    pub dwell: f64,
    /// Where the pen starts (for the travel in the header) and where the
    /// program parks it at the end (none: it stays after the last stroke).
    pub route: Route,
}

impl Default for GcodeOptions {
    fn default() -> Self {
        GcodeOptions {
            pen: Pen::M3,
            feed: 1500.0,
            dwell: 0.0,
            route: Route::closed(Pt::new(0.0, 0.0)),
        }
    }
}

/// A coordinate with at most 3 decimals and no trailing zeros.
pub fn num(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    let mut s = format!("{:.3}", if r == 0.0 { 0.0 } else { r });
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.pop();
    }
    s
}

fn pen_line(out: &mut String, o: &GcodeOptions, down: bool) {
    match o.pen {
        Pen::M3 => out.push_str(if down { "M3\n" } else { "M5\n" }),
        Pen::Z { up, down: dn, feed } => {
            if down {
                let _ = writeln!(out, "G1 Z{} F{}", num(dn), num(feed));
            } else {
                let _ = writeln!(out, "G0 Z{}", num(up));
            }
        }
    }
    if o.dwell > 0.0 {
        let _ = writeln!(out, "G4 P{}", num(o.dwell));
    }
}

/// The whole program for strokes already in drawing order.
pub fn to_gcode(strokes: &[Stroke], o: &GcodeOptions) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "(inkstep-host: {} strokes, pen-down {} mm, pen-up {} mm)",
        strokes.len(),
        num(pen_down_length(strokes)),
        num(pen_up_travel(strokes, o.route))
    );
    out.push_str("G21 G90 G94\n");
    pen_line(&mut out, o, false);
    for s in strokes.iter().filter(|s| !s.is_empty()) {
        let _ = writeln!(out, "G0 X{} Y{}", num(s[0].x), num(s[0].y));
        pen_line(&mut out, o, true);
        let mut first = true;
        for p in &s[1..] {
            if first {
                let _ = writeln!(out, "G1 X{} Y{} F{}", num(p.x), num(p.y), num(o.feed));
                first = false;
            } else {
                let _ = writeln!(out, "G1 X{} Y{}", num(p.x), num(p.y));
            }
        }
        pen_line(&mut out, o, false);
    }
    if let Some(p) = o.route.park {
        let _ = writeln!(out, "G0 X{} Y{}", num(p.x), num(p.y));
    }
    out.push_str("M2\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath::{check_grbl, parse, MoveKind};

    #[test]
    fn numbers_are_short() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-0.0001), "0");
        assert_eq!(num(12.34567), "12.346");
        assert_eq!(num(-3.5), "-3.5");
    }

    #[test]
    fn program_parses_and_replays_the_strokes() {
        let strokes = vec![
            vec![Pt::new(1.0, 1.0), Pt::new(2.0, 1.0), Pt::new(2.0, 3.0)],
            vec![Pt::new(5.0, 5.0), Pt::new(6.0, 6.5)],
        ];
        for pen in [
            Pen::M3,
            Pen::Z {
                up: 5.0,
                down: 0.0,
                feed: 500.0,
            },
        ] {
            let o = GcodeOptions {
                pen,
                dwell: 0.1,
                ..Default::default()
            };
            let g = to_gcode(&strokes, &o);
            check_grbl(&g).unwrap();
            let moves = parse(&g).unwrap();
            let drawn: Vec<_> = moves.iter().filter(|m| m.kind == MoveKind::Draw).collect();
            assert_eq!(drawn.len(), 3);
            assert_eq!(
                (drawn[0].from, drawn[0].to),
                (Pt::new(1.0, 1.0), Pt::new(2.0, 1.0))
            );
            assert_eq!(drawn[2].to, Pt::new(6.0, 6.5));
            let travel: f64 = moves
                .iter()
                .filter(|m| m.kind == MoveKind::Travel)
                .map(|m| m.from.dist(m.to))
                .sum();
            // To the first stroke, between strokes, and home.
            // From the origin (where the reader starts), between strokes, and the park.
            let expect = pen_up_travel(&strokes, o.route);
            assert!((travel - expect).abs() < 1e-5, "{travel} {expect}");
            assert!(
                (expect
                    - pen_up_travel(&strokes, Route::open(o.route.start))
                    - Pt::new(6.0, 6.5).dist(Pt::new(0.0, 0.0)))
                .abs()
                    < 1e-9
            );
        }
    }
}
