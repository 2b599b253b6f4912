//! Reading G-code back: a small parser for the dialect the tool writes and
//! for sender files (G0-G3 with I/J or R arcs flattened, G20/G21, G90/G91,
//! M3/M5 or a Z pen), used by the preview and by the Grbl-compatibility check. It is not the
//! firmware's interpreter (that lives in inkstep-core); it only needs the
//! XY path and whether the pen is down.

use crate::geom::Pt;
use anyhow::{bail, Result};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MoveKind {
    /// Pen down, G1 (or G2/G3 chords are not produced by this tool).
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
}

/// Removes `( ... )` and `;` comments and surrounding space.
pub fn strip_comment(line: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in line.chars() {
        match c {
            ';' if depth == 0 => break,
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out.trim().to_string()
}

/// Words of a line as (letter, value), upper-cased.
pub fn words(line: &str) -> Result<Vec<(char, f64)>> {
    let s: String = strip_comment(line)
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    let mut out = Vec::new();
    let b = s.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let letter = (b[i] as char).to_ascii_uppercase();
        if !letter.is_ascii_alphabetic() {
            bail!("expected a letter at {:?}", &s[i..]);
        }
        let j = i
            + 1
            + s[i + 1..]
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
                .unwrap_or(s.len() - i - 1);
        let v: f64 = s[i + 1..j]
            .parse()
            .map_err(|_| anyhow::anyhow!("bad number after {letter}"))?;
        out.push((letter, v));
        i = j;
    }
    Ok(out)
}

/// The XY moves of a program, with pen state. With no M3 in the file the
/// pen is taken to be Z: down below the middle of the Z values used; with
/// neither, every feed move (G1-G3) draws.
pub fn parse(text: &str) -> Result<Vec<Move>> {
    let lines: Vec<Vec<(char, f64)>> = text
        .lines()
        .enumerate()
        .map(|(k, l)| {
            // Grbl system commands ($...) and tape marks (%) move nothing.
            let t = strip_comment(l);
            if t.starts_with('$') || t.starts_with('%') {
                return Ok(Vec::new());
            }
            words(l).map_err(|e| anyhow::anyhow!("line {}: {e}", k + 1))
        })
        .collect::<Result<_>>()?;
    let uses_m3 = lines
        .iter()
        .flatten()
        .any(|&(c, v)| c == 'M' && (v == 3.0 || v == 4.0));
    let zs: Vec<f64> = lines
        .iter()
        .flatten()
        .filter(|w| w.0 == 'Z')
        .map(|w| w.1)
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
    let mut out = Vec::new();
    for (k, ws) in lines.iter().enumerate() {
        let (mut x, mut y, mut nz) = (None, None, None);
        let (mut i, mut j, mut r) = (0.0, 0.0, None);
        for &(c, v) in ws {
            match (c, v) {
                ('G', g) if g == 0.0 || g == 1.0 || g == 2.0 || g == 3.0 => motion = g as u8,
                ('G', 20.0) => scale = 25.4,
                ('G', 21.0) => scale = 1.0,
                ('G', 90.0) => absolute = true,
                ('G', 91.0) => absolute = false,
                ('M', m) if m == 3.0 || m == 4.0 => m3 = true,
                ('M', m) if m == 5.0 || m == 2.0 || m == 30.0 => m3 = false,
                ('X', v) => x = Some(v * scale),
                ('Y', v) => y = Some(v * scale),
                ('Z', v) => nz = Some(v * scale),
                ('I', v) => i = v * scale,
                ('J', v) => j = v * scale,
                ('R', v) => r = Some(v * scale),
                _ => {}
            }
        }
        if let Some(v) = nz {
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
        if motion == 2 || motion == 3 {
            let pts = arc_points(pos, to, i, j, r, motion == 2, 0.01)
                .map_err(|e| anyhow::anyhow!("line {}: {e}", k + 1))?;
            let mut from = pos;
            for p in pts {
                out.push(Move {
                    from,
                    to: p,
                    kind,
                    line: k + 1,
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
        });
        pos = to;
    }
    Ok(out)
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
/// emits: known words only, supported G and M numbers, at most 80 characters.
pub fn check_grbl(text: &str) -> Result<()> {
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        if line.len() > 80 {
            bail!("line {n}: longer than Grbl's 80-character buffer");
        }
        if !line.is_ascii() {
            bail!("line {n}: not ASCII");
        }
        for (c, v) in words(line).map_err(|e| anyhow::anyhow!("line {n}: {e}"))? {
            let ok = match c {
                'G' => [0.0, 1.0, 4.0, 20.0, 21.0, 90.0, 91.0, 94.0].contains(&v),
                'M' => [2.0, 3.0, 5.0, 30.0].contains(&v),
                'X' | 'Y' | 'Z' | 'F' | 'P' | 'S' => v.is_finite(),
                _ => false,
            };
            if !ok {
                bail!("line {n}: unsupported word {c}{v}");
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_and_comments() {
        assert_eq!(
            words("g1x1.5 Y-2 (c) ; rest").unwrap(),
            vec![('G', 1.0), ('X', 1.5), ('Y', -2.0)]
        );
        assert!(words("G1 X").is_err());
        assert!(words("#1=2").is_err());
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
        assert!(check_grbl("G2 X1 Y1 I1").is_err());
        assert!(check_grbl(&format!("G1 X{}", "1".repeat(90))).is_err());
    }
}
