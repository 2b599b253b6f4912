//! What a G-code program draws: its XY moves, each marked pen-down or travel, read
//! with the firmware's own G-code parser (inkstep-core: the line cleaner and the word
//! parser, so a file reads here exactly as the board will read it, with Grbl's error
//! numbers). The host keeps only what the core does not do for it: the modal state a
//! path needs (G0-G3, G20/G21, G90/G91, M3/M5 or a Z pen) and arcs flattened in f64.
//! Used by the preview, the planning benchmark, the web view and the
//! Grbl-compatibility check of what the tool writes.

use crate::geom::Pt;
use anyhow::{anyhow, bail, Result};
use inkstep_core::gcode::parser::WordBlock;
use inkstep_core::gcode::LineCleaner;
use inkstep_serial::grbl::error_text;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MoveKind {
    /// Pen down and a feed move (G1-G3).
    Draw,
    /// Pen up or rapid.
    Travel,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    pub from: Pt,
    pub to: Pt,
    pub kind: MoveKind,
    /// 1-based line in the file.
    pub line: usize,
    /// Feed in mm/min for feed moves (as the modal F stood), None for rapids.
    pub feed: Option<f64>,
}

/// A line cleaned as Grbl cleans it (comments, spaces gone, upper case) and parsed
/// into its block; None for lines that move nothing (empty, `$` commands, `%`).
pub fn block(line: &str) -> Result<Option<WordBlock>, u8> {
    let mut c = LineCleaner::new();
    let clean: Vec<u8> = line.bytes().filter_map(|b| c.push(b)).collect();
    if clean.is_empty() || clean[0] == b'$' || clean[0] == b'%' {
        return Ok(None);
    }
    WordBlock::parse(&clean).map(Some).map_err(|s| s.code())
}

fn blocks(text: &str) -> Result<Vec<Option<WordBlock>>> {
    text.lines()
        .enumerate()
        .map(|(k, l)| {
            block(l).map_err(|n| anyhow!("line {}: error:{n} ({})", k + 1, error_text(n.into())))
        })
        .collect()
}

fn value(b: &WordBlock, letter: u8) -> Option<f64> {
    b.get(letter).map(|v| v.millionths() as f64 / 1e6)
}

/// The XY moves of a program, with pen state. With no M3 in the file the
/// pen is taken to be Z: down below the middle of the Z values used; with
/// neither, every feed move (G1-G3) draws.
pub fn parse(text: &str) -> Result<Vec<Move>> {
    let lines = blocks(text)?;
    let uses_m3 = lines
        .iter()
        .flatten()
        .any(|b| b.m.iter().any(|&m| m == 30 || m == 40));
    let zs: Vec<f64> = lines
        .iter()
        .flatten()
        .filter_map(|b| value(b, b'Z'))
        .collect();
    let zmid = if zs.is_empty() {
        f64::NEG_INFINITY
    } else {
        let lo = zs.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = zs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        (lo + hi) / 2.0
    };
    let (mut pos, mut z) = (Pt::new(0.0, 0.0), 0.0);
    let (mut motion, mut absolute, mut scale, mut m3) = (0, true, 1.0, false);
    let mut feed = None;
    let mut out = Vec::new();
    for (k, b) in lines.iter().enumerate() {
        let Some(b) = b else { continue };
        for &g in &b.g {
            match g {
                0 | 10 | 20 | 30 => motion = g / 10,
                200 => scale = 25.4,
                210 => scale = 1.0,
                900 => absolute = true,
                910 => absolute = false,
                _ => {}
            }
        }
        for &m in &b.m {
            match m {
                30 | 40 => m3 = true,
                20 | 50 | 300 => m3 = false,
                _ => {}
            }
        }
        if let Some(f) = value(b, b'F') {
            feed = Some(f * scale);
        }
        let (x, y) = (
            value(b, b'X').map(|v| v * scale),
            value(b, b'Y').map(|v| v * scale),
        );
        if let Some(v) = value(b, b'Z') {
            let v = v * scale;
            z = if absolute { v } else { z + v };
        }
        if x.is_none() && y.is_none() {
            continue;
        }
        let to = if absolute {
            Pt::new(x.unwrap_or(pos.x), y.unwrap_or(pos.y))
        } else {
            Pt::new(pos.x + x.unwrap_or(0.0), pos.y + y.unwrap_or(0.0))
        };
        // No pen commands at all: every feed move draws.
        let down = if uses_m3 {
            m3
        } else {
            zs.is_empty() || z < zmid
        };
        let kind = if motion != 0 && down {
            MoveKind::Draw
        } else {
            MoveKind::Travel
        };
        let feed = (motion != 0).then_some(feed).flatten();
        if motion == 2 || motion == 3 {
            let (i, j) = (
                value(b, b'I').unwrap_or(0.0) * scale,
                value(b, b'J').unwrap_or(0.0) * scale,
            );
            let r = value(b, b'R').map(|r| r * scale);
            let pts = arc_points(pos, to, i, j, r, motion == 2, 0.01)
                .map_err(|e| anyhow!("line {}: {e}", k + 1))?;
            let mut from = pos;
            for p in pts {
                out.push(Move {
                    from,
                    to: p,
                    kind,
                    line: k + 1,
                    feed,
                });
                from = p;
            }
            pos = to;
            continue;
        }
        out.push(Move {
            from: pos,
            to,
            kind,
            line: k + 1,
            feed,
        });
        pos = to;
    }
    Ok(out)
}

/// Pen-up travel of a program: the length of every move that does not draw.
pub fn travel(moves: &[Move]) -> f64 {
    moves
        .iter()
        .filter(|m| m.kind == MoveKind::Travel)
        .map(|m| m.from.dist(m.to))
        .sum()
}

/// Points after `from` along a G2 (`cw`) or G3 arc in the XY plane to `to`,
/// with the centre at `from + (i, j)` or from the radius `r` (negative: the
/// arc longer than half a circle), each chord within `tol` of the arc. The
/// last point is `to` exactly.
pub fn arc_points(
    from: Pt,
    to: Pt,
    i: f64,
    j: f64,
    r: Option<f64>,
    cw: bool,
    tol: f64,
) -> Result<Vec<Pt>> {
    let centre = match r {
        None => Pt::new(from.x + i, from.y + j),
        Some(r) => {
            let (dx, dy) = (to.x - from.x, to.y - from.y);
            let d = dx.hypot(dy);
            if d == 0.0 {
                bail!("R-form arc with coincident end points");
            }
            let h2 = r * r - d * d / 4.0;
            if h2 < -1e-9 * r * r.max(1.0) {
                bail!("arc radius {r} too small for the chord {d}");
            }
            // Offset of the centre from the chord midpoint, to the right of
            // the chord for a clockwise arc of at most half a turn.
            let mut h = h2.max(0.0).sqrt() / d;
            if !cw {
                h = -h;
            }
            if r < 0.0 {
                h = -h;
            }
            Pt::new(from.x + dx / 2.0 + dy * h, from.y + dy / 2.0 - dx * h)
        }
    };
    let rad = from.dist(centre);
    let a0 = (from.y - centre.y).atan2(from.x - centre.x);
    let a1 = (to.y - centre.y).atan2(to.x - centre.x);
    let tau = std::f64::consts::TAU;
    let mut sweep = a1 - a0;
    if cw {
        while sweep >= 0.0 {
            sweep -= tau;
        }
        if sweep <= -tau {
            sweep += tau;
        }
        // Same start and end with I/J: a full circle.
        if from.dist(to) < 1e-9 {
            sweep = -tau;
        }
    } else {
        while sweep <= 0.0 {
            sweep += tau;
        }
        if sweep >= tau {
            sweep -= tau;
        }
        if from.dist(to) < 1e-9 {
            sweep = tau;
        }
    }
    let step = if rad > tol {
        2.0 * (1.0 - tol / rad).acos()
    } else {
        tau
    };
    let n = ((sweep.abs() / step).ceil() as usize).clamp(1, 100_000);
    let mut pts: Vec<Pt> = (1..n)
        .map(|k| {
            let a = a0 + sweep * k as f64 / n as f64;
            Pt::new(centre.x + rad * a.cos(), centre.y + rad * a.sin())
        })
        .collect();
    pts.push(to);
    Ok(pts)
}

/// Checks that every line is plain Grbl 1.1 G-code of the kind this tool
/// emits: known words only, supported G and M numbers, at most the board's
/// line length (80 characters, as Grbl's).
pub fn check_grbl(text: &str) -> Result<()> {
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        if line.len() > inkstep_core::gcode::LINE_MAX {
            bail!("line {n}: longer than the board's 80-character line buffer");
        }
        if !line.is_ascii() {
            bail!("line {n}: not ASCII");
        }
        let Some(b) = block(line).map_err(|e| anyhow!("line {n}: error:{e}"))? else {
            continue;
        };
        if let Some(g) =
            b.g.iter()
                .find(|g| ![0, 10, 20, 30, 40, 200, 210, 900, 910, 940].contains(*g))
        {
            bail!("line {n}: unsupported G{}", f64::from(*g) / 10.0);
        }
        if let Some(m) = b.m.iter().find(|m| ![20, 30, 50, 60, 300].contains(*m)) {
            bail!("line {n}: unsupported M{}", f64::from(*m) / 10.0);
        }
        if let Some(l) = (b'A'..=b'Z').find(|&l| b.get(l).is_some() && !b"XYZFPSIJT".contains(&l)) {
            bail!("line {n}: unsupported word {}", char::from(l));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_and_comments() {
        let m = parse("g1x1.5 Y-2 F600 (c) ; rest").unwrap();
        assert_eq!(m[0].to, Pt::new(1.5, -2.0));
        assert_eq!(m[0].feed, Some(600.0));
        assert!(parse("G1 X").is_err());
        assert!(parse("#1=2").unwrap_err().to_string().contains("error:1"));
    }

    #[test]
    fn relative_inches_and_z_pen() {
        let m = parse("$100=80\n%\nG20 G91\nG0 X1\nG1 Z-1\nG1 Y1\nG0 Z1\nG1 X1\n").unwrap();
        assert_eq!(m.len(), 3);
        assert_eq!(m[0].to, Pt::new(25.4, 0.0));
        assert_eq!(m[1].kind, MoveKind::Draw);
        assert_eq!(m[1].to, Pt::new(25.4, 25.4));
        assert_eq!(m[2].kind, MoveKind::Travel);
        assert_eq!(m[2].line, 8);
    }

    #[test]
    fn arcs_in_both_forms_follow_the_circle() {
        // Quarter circles of radius 10 about the origin, from (10,0) to (0,10).
        let ccw = parse("G0 X10 Y0\nM3\nG3 X0 Y10 I-10 J0\n").unwrap();
        let cw_r = parse("G0 X10 Y0\nM3\nG2 X0 Y10 R-10\n").unwrap();
        for (moves, quarter) in [(&ccw, 1.0), (&cw_r, 3.0)] {
            let arc: Vec<_> = moves.iter().filter(|m| m.kind == MoveKind::Draw).collect();
            assert!(arc.len() > 10);
            assert_eq!(arc.last().unwrap().to, Pt::new(0.0, 10.0));
            let mut len = 0.0;
            for m in &arc {
                assert!((m.to.dist(Pt::new(0.0, 0.0)) - 10.0).abs() < 1e-9);
                len += m.from.dist(m.to);
            }
            // Chord length just under the arc length (quarter or three quarters).
            let arc_len = quarter * std::f64::consts::FRAC_PI_2 * 10.0;
            assert!(
                len < arc_len && len > arc_len * (1.0 - 1e-3),
                "{len} {arc_len}"
            );
        }
        // A full circle with I/J.
        let full = parse("G0 X5 Y0\nM3\nG2 X5 Y0 I-5 J0\n").unwrap();
        let len: f64 = full
            .iter()
            .filter(|m| m.kind == MoveKind::Draw)
            .map(|m| m.from.dist(m.to))
            .sum();
        assert!((len - std::f64::consts::TAU * 5.0).abs() < 0.05, "{len}");
        assert!(parse("G2 X100 Y0 R1").is_err());
        // No pen commands: feed moves draw, rapids travel.
        let plain = parse("G0 X1\nG1 X2\n").unwrap();
        assert_eq!(
            (plain[0].kind, plain[1].kind),
            (MoveKind::Travel, MoveKind::Draw)
        );
    }

    #[test]
    fn grbl_check_rejects_unsupported() {
        assert!(check_grbl("G21 G90\nG0 X1 Y2\nM3\nG1 X2 F100\nM5\nM2\n").is_ok());
        assert!(check_grbl("G2 X1 Y1 I1").is_ok());
        assert!(check_grbl("G2 X1 Y1 K1").is_err());
        assert!(check_grbl("G28").is_err());
        assert!(check_grbl(&format!("G1 X{}", "1".repeat(90))).is_err());
    }
}
