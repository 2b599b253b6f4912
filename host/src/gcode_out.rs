//! Strokes to G-code, in the plain Grbl dialect the firmware and the
//! simulator accept: G21 G90, pen-up travel as G0, pen-down strokes as G1
//! with F, and the pen lifted and dropped either by M5/M3 (the firmware maps
//! them to the servo or Z, as its settings say) or by moving Z explicitly.
//! The program ends by parking the pen where the route says (a G0 there).
//! Lines stay short (well under Grbl's 80-character line buffer): coordinates
//! are refused beyond +-[`MAX_COORD`] mm before writing ([`check_coords`]),
//! which bounds every word, and a layer name in a message is cut to fit.
//!
//! A drawing of several passes (layers, colours) gets a pen change between
//! passes: pen up, `(MSG,...)` naming the next layer, `M6 T<n>`. With
//! `arcs`, runs of points on a circle go out as G2/G3 (see `arcs`).

use crate::arcs::{fit, Piece};
use crate::biarc::ArcHints;
use crate::geom::{pen_down_length, pen_up_travel, Pt, Route, Stroke};
use anyhow::{bail, Result};
use inkstep_core::gcode::LINE_MAX;
use std::fmt::Write as _;

/// Largest coordinate written (mm). With 3 decimals a word is at most 12
/// characters, so the longest line (an arc: G3 X Y I J F) stays under
/// [`LINE_MAX`].
pub const MAX_COORD: f64 = 100_000.0;

/// How the pen is lifted and dropped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pen {
    /// M3 drops the pen, M5 lifts it.
    M3,
    /// Z moves: `up` and `down` heights (mm), Z moved at `feed` mm/min.
    Z { up: f64, down: f64, feed: f64 },
}

#[derive(Clone, Debug)]
pub struct GcodeOptions {
    pub pen: Pen,
    /// Drawing feed (mm/min).
    pub feed: f64,
    /// Dwell after each pen move (s), 0 for none.
    pub dwell: f64,
    /// Where the pen starts (for the travel in the header) and where the
    /// program parks it at the end (none: it stays after the last stroke).
    pub route: Route,
    /// Fit arcs (G2/G3) within this tolerance (mm); None: lines only.
    pub arcs: Option<f64>,
    /// Arcs known from the curves they stand for (`svg --arcs`): a pair of
    /// consecutive points found here goes out as that arc; the runs between
    /// them are fitted as `arcs` says.
    pub arc_hints: ArcHints,
}

/// One pass of the pen (a layer or a colour), drawn in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Pass {
    pub name: String,
    pub strokes: Vec<Stroke>,
}

impl Default for GcodeOptions {
    fn default() -> Self {
        GcodeOptions {
            pen: Pen::M3,
            feed: 1500.0,
            dwell: 0.0,
            route: Route::closed(Pt::new(0.0, 0.0)),
            arcs: None,
            arc_hints: ArcHints::default(),
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

fn stroke_lines(out: &mut String, s: &[Pt], o: &GcodeOptions) {
    let _ = writeln!(out, "G0 X{} Y{}", num(s[0].x), num(s[0].y));
    pen_line(out, o, true);
    let run = |r: &[Pt]| -> Vec<Piece> {
        match o.arcs {
            Some(tol) => fit(r, tol),
            None => r[1..].iter().map(|&p| Piece::Line(p)).collect(),
        }
    };
    let pieces: Vec<Piece> = if o.arc_hints.is_empty() {
        run(s)
    } else {
        // Known arcs as they are; the points between them fitted as above.
        let mut pieces = Vec::new();
        let mut begin = 0;
        for k in 1..s.len() {
            if let Some((centre, ccw)) = o.arc_hints.get(s[k - 1], s[k]) {
                if k - 1 > begin {
                    pieces.extend(run(&s[begin..k]));
                }
                pieces.push(Piece::Arc {
                    to: s[k],
                    centre,
                    ccw,
                });
                begin = k;
            }
        }
        if s.len() - 1 > begin {
            pieces.extend(run(&s[begin..]));
        }
        pieces
    };
    let mut from = s[0];
    for (k, piece) in pieces.iter().enumerate() {
        let f = if k == 0 {
            format!(" F{}", num(o.feed))
        } else {
            String::new()
        };
        match *piece {
            Piece::Line(p) => {
                let _ = writeln!(out, "G1 X{} Y{}{f}", num(p.x), num(p.y));
                from = p;
            }
            Piece::Arc { to, centre, ccw } => {
                let _ = writeln!(
                    out,
                    "G{} X{} Y{} I{} J{}{f}",
                    if ccw { 3 } else { 2 },
                    num(to.x),
                    num(to.y),
                    num(centre.x - from.x),
                    num(centre.y - from.y)
                );
                from = to;
            }
        }
    }
    pen_line(out, o, false);
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

/// Refuses coordinates that are not finite or beyond +-[`MAX_COORD`] mm, and
/// feeds or dwells that would not print short.
pub fn check_coords(strokes: &[Stroke], o: &GcodeOptions) -> Result<()> {
    let ok = |p: &Pt| p.x.abs() <= MAX_COORD && p.y.abs() <= MAX_COORD;
    if let Some(p) = strokes.iter().flatten().find(|p| !ok(p)) {
        bail!(
            "coordinate ({:e}, {:e}) mm is beyond +-{MAX_COORD} mm: nothing written",
            p.x,
            p.y
        );
    }
    let route = [Some(o.route.start), o.route.park];
    if route.iter().flatten().any(|p| !ok(p)) {
        bail!("start or park beyond +-{MAX_COORD} mm");
    }
    if !(o.feed > 0.0 && o.feed <= 1e6 && o.dwell >= 0.0 && o.dwell <= 1e6) {
        bail!("feed must be in (0, 1e6] mm/min and dwell in [0, 1e6] s");
    }
    if let Pen::Z { up, down, feed } = o.pen {
        if !(up.abs() <= 1e4 && down.abs() <= 1e4 && feed > 0.0 && feed <= 1e6) {
            bail!("Z heights must be within +-10000 mm and the Z feed in (0, 1e6] mm/min");
        }
    }
    Ok(())
}

/// A layer name as it may go in a `(MSG,...)` comment: printable ASCII
/// without parentheses, cut so that the line fits.
fn msg_text(name: &str, room: usize) -> String {
    let t: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_graphic() && c != '(' && c != ')' || c == ' ' {
                c
            } else {
                '_'
            }
        })
        .collect();
    t.chars().take(room).collect()
}

/// The whole program for strokes already in drawing order.
pub fn to_gcode(strokes: &[Stroke], o: &GcodeOptions) -> String {
    to_gcode_passes(
        &[Pass {
            name: String::new(),
            strokes: strokes.to_vec(),
        }],
        o,
    )
}

/// The whole program for passes drawn one after another, each already in
/// drawing order; a pen change (M6) before each pass after the first.
pub fn to_gcode_passes(passes: &[Pass], o: &GcodeOptions) -> String {
    let all: Vec<Stroke> = passes
        .iter()
        .flat_map(|p| p.strokes.iter().cloned())
        .collect();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "(inkstep-host: {} strokes, pen-down {} mm, pen-up {} mm)",
        all.len(),
        num(pen_down_length(&all)),
        num(pen_up_travel(&all, o.route))
    );
    out.push_str("G21 G90 G94\n");
    pen_line(&mut out, o, false);
    let changes = passes.len() > 1;
    for (k, pass) in passes.iter().enumerate() {
        if changes {
            // "(MSG," + name + ")": the name gets what is left of the line.
            let name = if pass.name.is_empty() {
                format!("pass {}", k + 1)
            } else {
                pass.name.clone()
            };
            let _ = writeln!(
                out,
                "(MSG,pen {}: {})",
                k + 1,
                msg_text(&name, LINE_MAX - 20)
            );
            if k > 0 {
                let _ = writeln!(out, "M6 T{}", k + 1);
            }
        }
        for s in pass.strokes.iter().filter(|s| !s.is_empty()) {
            stroke_lines(&mut out, s, o);
        }
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
