//! A model of Grbl 1.1's planner, to give a reference job time for programs that Grbl's
//! own simulator (grbl-sim) was not run on: the bench's programs of tiny moves.
//!
//! Owns the reference, not anything inkstep does: this is a second planner, written here
//! from Grbl's documented behaviour and the maths (no line of Grbl's code), and it
//! shares nothing with inkstep's core, so the two can disagree. What it models:
//! - the program's targets rounded to whole steps, each block's length and direction
//!   taken from the step counts;
//! - per-axis limits: along direction u the path acceleration is min_i a_i/|u_i| and the
//!   speed min(F, min_i v_i/|u_i|);
//! - junction deviation: at a corner of angle theta the entry speed is limited to
//!   v^2 = a_j delta sin(theta/2) / (1 - sin(theta/2)), a_j the per-axis acceleration
//!   limit along the change of direction; no minimum junction speed (a reversal stops);
//! - arcs as chords, as many as the arc tolerance $12 asks:
//!   floor(|theta r / 2| / sqrt(tol (2 r - tol))) (Grbl's documented rule);
//! - constant-acceleration (trapezoid) ramps, starting and ending at rest;
//! - a look-ahead of [`GRBL_328P_BLOCKS`] blocks: a block's exit speed is planned from
//!   the blocks the buffer can hold when it runs (the 328p's ring of 16 slots holds 15,
//!   the block in execution among them); the last of them is planned to stop.
//!
//! Time is the ideal profile's: steps are not generated, so Grbl's segment timing and
//! AMASS are not in it. Checked against grbl-sim's figures for the four programs it was
//! run on (`bench/GRBL.md`): within 0.07 % (the golden tests assert 0.1 %).

use std::fmt;

/// Blocks in Grbl 1.1's planner buffer on an ATmega328p, the block in execution included.
pub const GRBL_328P_BLOCKS: usize = 15;

/// How far the model plans ahead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lookahead {
    /// At most this many blocks, the one in execution included.
    Blocks(usize),
    /// The whole program: the time-optimal profile for the limits.
    Unbounded,
}

/// Limits of the X and Y axes and the planner settings, as in Grbl's `$` settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// $100, $101: steps per mm.
    pub steps_per_mm: [f64; 2],
    /// $110, $111: mm/min.
    pub max_rate: [f64; 2],
    /// $120, $121: mm/s^2.
    pub accel: [f64; 2],
    /// $11: mm.
    pub junction_deviation: f64,
    /// $12: mm.
    pub arc_tolerance: f64,
    /// Path speed (mm/s) that replaces rest at the start, the end and reversals, and
    /// below which no junction is planned. Grbl has none (0); inkstep's $213.
    pub floor: f64,
}

impl Default for Limits {
    /// Grbl 1.1's defaults where the bench programs do not set them.
    fn default() -> Self {
        Limits {
            steps_per_mm: [250.0; 2],
            max_rate: [500.0; 2],
            accel: [10.0; 2],
            junction_deviation: 0.01,
            arc_tolerance: 0.002,
            floor: 0.0,
        }
    }
}

/// A word the model does not know.
#[derive(Clone, Debug, PartialEq)]
pub struct Unsupported(pub String);

impl fmt::Display for Unsupported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the Grbl model does not read {:?}", self.0)
    }
}

/// One straight move: its end in mm, its feed in mm/min (`None`: rapid), and whether it
/// is a chord of an arc.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Target {
    xy: [f64; 2],
    feed: Option<f64>,
    chord: bool,
}

/// The limits a program sets and its moves: `$1xx=` and `$11`/`$12` settings, G0/G1
/// lines and G2/G3 arcs with I/J in the XY plane, absolute millimetres (G21 G90 G17
/// G94 are accepted), G4 ignored.
fn read_program(text: &str) -> Result<(Limits, Vec<Target>), Unsupported> {
    let mut lim = Limits::default();
    let mut pos = [0.0f64; 2];
    let mut feed = None;
    let mut motion = 0u32;
    let mut out = Vec::new();
    for raw in text.lines() {
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(setting) = line.strip_prefix('$') {
            let bad = || Unsupported(line.to_string());
            let (n, v) = setting.split_once('=').ok_or_else(bad)?;
            let v: f64 = v.trim().parse().map_err(|_| bad())?;
            match n.trim() {
                "100" => lim.steps_per_mm[0] = v,
                "101" => lim.steps_per_mm[1] = v,
                "110" => lim.max_rate[0] = v,
                "111" => lim.max_rate[1] = v,
                "120" => lim.accel[0] = v,
                "121" => lim.accel[1] = v,
                "11" => lim.junction_deviation = v,
                "12" => lim.arc_tolerance = v,
                _ => return Err(bad()),
            }
            continue;
        }
        let mut words: Vec<(char, f64)> = Vec::new();
        let mut rest = line;
        while let Some(c) = rest.chars().next() {
            let end = rest[1..]
                .find(|ch: char| ch.is_ascii_alphabetic())
                .map_or(rest.len(), |i| i + 1);
            let v: f64 = rest[1..end]
                .trim()
                .parse()
                .map_err(|_| Unsupported(line.to_string()))?;
            words.push((c.to_ascii_uppercase(), v));
            rest = rest[end..].trim_start();
        }
        let word = |k: char| words.iter().find(|w| w.0 == k).map(|w| w.1);
        let mut dwell = false;
        for &(k, v) in &words {
            match (k, v as u32) {
                ('G', 0..=3) => motion = v as u32,
                ('G', 4) => dwell = true,
                ('G', 17 | 21 | 90 | 94) => {}
                ('X' | 'Y' | 'I' | 'J' | 'R' | 'F', _) => {}
                ('P', _) if dwell => {}
                _ => return Err(Unsupported(line.to_string())),
            }
        }
        if let Some(f) = word('F') {
            feed = Some(f);
        }
        if dwell || (word('X').is_none() && word('Y').is_none()) {
            continue;
        }
        let target = [word('X').unwrap_or(pos[0]), word('Y').unwrap_or(pos[1])];
        let feed = if motion == 0 { None } else { feed };
        if motion >= 2 {
            let centre = match word('R') {
                Some(r) => radius_centre(pos, target, r, motion == 2)
                    .ok_or_else(|| Unsupported(line.to_string()))?,
                None => [
                    pos[0] + word('I').unwrap_or(0.0),
                    pos[1] + word('J').unwrap_or(0.0),
                ],
            };
            chords(
                &mut out,
                pos,
                target,
                centre,
                motion == 2,
                lim.arc_tolerance,
                feed,
            );
        } else {
            out.push(Target {
                xy: target,
                feed,
                chord: false,
            });
        }
        pos = target;
    }
    Ok((lim, out))
}

/// The centre of an R-form arc, as the G-code standard defines it: on the chord's
/// perpendicular bisector, to the right of the chord for a clockwise arc of at most half
/// a turn (R > 0), to the left for the longer arc (R < 0); mirrored for
/// counter-clockwise. `None` when the radius is shorter than half the chord (beyond
/// rounding) or the ends coincide.
fn radius_centre(from: [f64; 2], to: [f64; 2], r: f64, cw: bool) -> Option<[f64; 2]> {
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    let d = dx.hypot(dy);
    if d == 0.0 {
        return None;
    }
    let h2 = r * r - 0.25 * d * d;
    if h2 < -1e-6 * r * r {
        return None;
    }
    let h = h2.max(0.0).sqrt();
    // Unit vector to the right of the travel direction.
    let right = [dy / d, -dx / d];
    let side = if cw == (r > 0.0) { h } else { -h };
    Some([
        0.5 * (from[0] + to[0]) + side * right[0],
        0.5 * (from[1] + to[1]) + side * right[1],
    ])
}

/// An arc from `from` to `to` around `centre` as chords within `tol` (clockwise when
/// `cw`; the same end point makes a full circle).
fn chords(
    out: &mut Vec<Target>,
    from: [f64; 2],
    to: [f64; 2],
    centre: [f64; 2],
    cw: bool,
    tol: f64,
    feed: Option<f64>,
) {
    use std::f64::consts::TAU;
    let r = (from[0] - centre[0]).hypot(from[1] - centre[1]);
    let a0 = (from[1] - centre[1]).atan2(from[0] - centre[0]);
    let a1 = (to[1] - centre[1]).atan2(to[0] - centre[0]);
    let mut turn = a1 - a0;
    if cw && turn >= -1e-7 {
        turn -= TAU;
    } else if !cw && turn <= 1e-7 {
        turn += TAU;
    }
    let n = ((0.5 * turn * r).abs() / (tol * (2.0 * r - tol)).sqrt()).floor() as usize;
    for i in 1..n {
        let a = a0 + turn * i as f64 / n as f64;
        let xy = [centre[0] + r * a.cos(), centre[1] + r * a.sin()];
        out.push(Target {
            xy,
            feed,
            chord: true,
        });
    }
    out.push(Target {
        xy: to,
        feed,
        chord: true,
    });
}

/// A planned block: length, path acceleration, top speed, and the highest entry speed
/// its junction allows (mm, mm/s^2, mm/s, mm/s).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Block {
    length: f64,
    accel: f64,
    top: f64,
    max_entry: f64,
}

/// min_i limit_i / |u_i| over the axes the direction `u` moves.
fn along(limit: [f64; 2], u: [f64; 2]) -> f64 {
    (0..2)
        .filter(|&i| u[i].abs() > 1e-12)
        .map(|i| limit[i] / u[i].abs())
        .fold(f64::INFINITY, f64::min)
}

/// The program's moves in steps from the origin.
#[derive(Clone, Debug, PartialEq)]
struct Stepped {
    blocks: Vec<Block>,
    /// Steps made on X and Y.
    steps: [u64; 2],
    /// Where the program ends, in steps.
    end: [i64; 2],
}

fn blocks(lim: &Limits, targets: &[Target]) -> Stepped {
    let spm = lim.steps_per_mm;
    let max_rate = [lim.max_rate[0] / 60.0, lim.max_rate[1] / 60.0];
    let mut at = [0i64; 2];
    let mut made = [0u64; 2];
    let mut prev: Option<([f64; 2], f64)> = None;
    let mut out = Vec::new();
    for t in targets {
        let steps = [
            (t.xy[0] * spm[0]).round() as i64,
            (t.xy[1] * spm[1]).round() as i64,
        ];
        let d = [
            (steps[0] - at[0]) as f64 / spm[0],
            (steps[1] - at[1]) as f64 / spm[1],
        ];
        let length = d[0].hypot(d[1]);
        if length == 0.0 {
            continue;
        }
        for (m, (s, a)) in made.iter_mut().zip(steps.iter().zip(at.iter())) {
            *m += s.abs_diff(*a);
        }
        at = steps;
        let u = [d[0] / length, d[1] / length];
        let rapid = along(max_rate, u);
        let top = t.feed.map_or(rapid, |f| (f / 60.0).min(rapid));
        let max_entry = match prev {
            None => lim.floor,
            Some((pu, ptop)) => {
                let cos = u[0] * pu[0] + u[1] * pu[1];
                let junction = if cos > 1.0 - 1e-6 {
                    f64::INFINITY
                } else if cos < -1.0 + 1e-6 {
                    0.0
                } else {
                    let j = [u[0] - pu[0], u[1] - pu[1]];
                    let n = j[0].hypot(j[1]);
                    let a = along(lim.accel, [j[0] / n, j[1] / n]);
                    // theta: the angle between the reversed incoming and the outgoing
                    // direction, so sin(theta / 2) = sqrt((1 + cos) / 2).
                    let s = (0.5 * (1.0 + cos)).sqrt();
                    (a * lim.junction_deviation * s / (1.0 - s)).sqrt()
                };
                junction.min(top).min(ptop).max(lim.floor.min(top))
            }
        };
        out.push(Block {
            length,
            accel: along(lim.accel, u),
            top,
            max_entry,
        });
        prev = Some((u, top));
    }
    Stepped {
        blocks: out,
        steps: made,
        end: at,
    }
}

/// Duration of a trapezoid over `b` from `v0` to `v1` (both reachable).
fn duration(b: &Block, v0: f64, v1: f64) -> f64 {
    let a = b.accel;
    let peak = (a * b.length + 0.5 * (v0 * v0 + v1 * v1)).sqrt().min(b.top);
    let ramps = (peak * peak - v0 * v0 + peak * peak - v1 * v1) / (2.0 * a);
    (peak - v0) / a + (peak - v1) / a + (b.length - ramps).max(0.0) / peak
}

/// Entry speeds of `w` (plus the exit of its last block, which stops at `floor`) when
/// the first block enters at `v0`: the reverse pass (each block can slow to the next),
/// then the forward pass (and reach it from the previous).
fn plan(w: &[Block], v0: f64, floor: f64) -> Vec<f64> {
    let mut v: Vec<f64> = w.iter().map(|b| b.max_entry).collect();
    v.push(floor);
    v[0] = v0;
    for i in (1..w.len()).rev() {
        let reach = (v[i + 1] * v[i + 1] + 2.0 * w[i].accel * w[i].length).sqrt();
        v[i] = v[i].min(reach);
    }
    for i in 1..=w.len() {
        let reach = (v[i - 1] * v[i - 1] + 2.0 * w[i - 1].accel * w[i - 1].length).sqrt();
        v[i] = v[i].min(reach);
    }
    v
}

/// Job time (s) of the blocks with the given look-ahead: each block runs from the speed
/// the previous one left at to the exit planned when it starts.
fn job_time_of(blocks: &[Block], look: Lookahead, floor: f64) -> f64 {
    match look {
        Lookahead::Unbounded => {
            let v = plan(blocks, floor, floor);
            blocks
                .iter()
                .enumerate()
                .map(|(i, b)| duration(b, v[i], v[i + 1]))
                .sum()
        }
        Lookahead::Blocks(n) => {
            let n = n.max(1);
            let mut v0 = floor;
            let mut t = 0.0;
            for k in 0..blocks.len() {
                let w = &blocks[k..(k + n).min(blocks.len())];
                let exit = plan(w, v0, floor)[1];
                t += duration(&w[0], v0, exit);
                v0 = exit;
            }
            t
        }
    }
}

/// The model's figures for one program.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelTimes {
    /// Blocks after rounding to steps (zero-length moves dropped).
    pub blocks: usize,
    /// Steps on X and Y, and the end position in steps.
    pub steps: [u64; 2],
    pub end: [i64; 2],
    /// Grbl 1.1 on a 328p: 15 blocks of look-ahead, no floor speed.
    pub grbl: f64,
    /// The time-optimal bound for the same limits with `floor` as the rest speed and
    /// the whole program as look-ahead; `None` for a program with arcs (their chords are
    /// Grbl's, not a bound for a planner that runs an arc as one curve).
    pub optimal: Option<f64>,
}

/// Job time of `text` under the model with `look` and the speed floor `floor` (mm/s).
pub fn job_time(text: &str, look: Lookahead, floor: f64) -> Result<f64, Unsupported> {
    let (lim, targets) = read_program(text)?;
    let lim = Limits { floor, ..lim };
    Ok(job_time_of(&blocks(&lim, &targets).blocks, look, floor))
}

/// Grbl's reference time and the time-optimal bound at inkstep's start speed `floor`.
pub fn times(text: &str, floor: f64) -> Result<ModelTimes, Unsupported> {
    let (lim, targets) = read_program(text)?;
    let arcs = targets.iter().any(|t| t.chord);
    let grbl = Limits { floor: 0.0, ..lim };
    let ours = Limits { floor, ..lim };
    let stepped = blocks(&grbl, &targets);
    Ok(ModelTimes {
        blocks: stepped.blocks.len(),
        steps: stepped.steps,
        end: stepped.end,
        grbl: job_time_of(&stepped.blocks, Lookahead::Blocks(GRBL_328P_BLOCKS), 0.0),
        optimal: (!arcs)
            .then(|| job_time_of(&blocks(&ours, &targets).blocks, Lookahead::Unbounded, floor)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str =
        "$100=80\n$101=80\n$110=5000\n$111=5000\n$120=500\n$121=500\n$11=0.01\nG21 G90\n";

    #[test]
    fn one_long_line_is_a_trapezoid() {
        // 100 mm along X at 50 mm/s, 500 mm/s^2: two 0.1 s ramps of 2.5 mm, 1.9 s cruise.
        let t = job_time(&format!("{HEAD}G1 X100 F3000\n"), Lookahead::Unbounded, 0.0);
        assert!((t.unwrap() - 2.1).abs() < 1e-12);
        // A diagonal accelerates faster along the path (500 sqrt 2) up to 5000 mm/min
        // on each axis: a triangle of 10 mm to a peak of sqrt(a L).
        let t = job_time(
            &format!("{HEAD}G1 X7.0711 Y7.0711 F10000\n"),
            Lookahead::Unbounded,
            0.0,
        );
        let (a, l) = (500.0 * 2f64.sqrt(), (2.0 * 566.0f64.powi(2)).sqrt() / 80.0);
        assert!((t.unwrap() - 2.0 * (l / a).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn a_right_angle_follows_the_junction_deviation_rule() {
        let (lim, targets) = read_program(&format!("{HEAD}G1 X10 F3000\nG1 Y10\n")).unwrap();
        let s = blocks(&lim, &targets);
        assert_eq!((s.steps, s.end), ([800, 800], [800, 800]));
        let b = s.blocks;
        let s = 0.5f64.sqrt();
        let expect = (500.0 * 2f64.sqrt() * 0.01 * s / (1.0 - s)).sqrt();
        assert!((b[1].max_entry - expect).abs() < 1e-9);
        assert_eq!(b[0].max_entry, 0.0);
    }

    #[test]
    fn a_short_lookahead_is_slower_on_many_collinear_moves() {
        let mut g = String::from(HEAD);
        for i in 1..=200 {
            g.push_str(&format!("G1 X{:.2} F5000\n", 0.05 * i as f64));
        }
        let short = job_time(&g, Lookahead::Blocks(GRBL_328P_BLOCKS), 0.0).unwrap();
        let long = job_time(&g, Lookahead::Blocks(100), 0.0).unwrap();
        let best = job_time(&g, Lookahead::Unbounded, 0.0).unwrap();
        assert!(best < long && long < short, "{best} {long} {short}");
        // 10 mm as one move is the same bound.
        let one = job_time(&format!("{HEAD}G1 X10 F5000\n"), Lookahead::Unbounded, 0.0);
        assert!((one.unwrap() - best).abs() < 1e-9);
    }

    #[test]
    fn arcs_become_chords_by_the_tolerance() {
        let (_, t) = read_program(&format!("{HEAD}$12=0.002\nG2 X0 Y0 I20 J0 F3000\n")).unwrap();
        // floor(pi 20 / sqrt(0.002 (40 - 0.002))) = 222 chords of a full circle.
        assert_eq!(t.len(), 222);
        assert!(t
            .iter()
            .all(|p| ((p.xy[0] - 20.0).hypot(p.xy[1]) - 20.0).abs() < 1e-9));
        assert_eq!(t.last().unwrap().xy, [0.0, 0.0]);
    }

    #[test]
    fn an_r_arc_has_the_centre_of_its_i_j_twin() {
        // A quarter circle of radius 10 about the origin, both ways, short and long.
        let c = |x, y, r, cw| radius_centre([10.0, 0.0], [x, y], r, cw).unwrap();
        let near = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9;
        assert!(near(c(0.0, 10.0, 10.0, false), [0.0, 0.0]));
        assert!(near(c(0.0, -10.0, 10.0, true), [0.0, 0.0]));
        assert!(near(c(0.0, 10.0, -10.0, true), [0.0, 0.0]));
        assert!(near(c(0.0, 10.0, 10.0, true), [10.0, 10.0]));
        assert!(radius_centre([0.0, 0.0], [10.0, 0.0], 4.0, true).is_none());
        let ij = read_program(&format!("{HEAD}G0 X10\nG3 X0 Y10 I-10 J0 F3000\n"))
            .unwrap()
            .1;
        let r = read_program(&format!("{HEAD}G0 X10\nG3 X0 Y10 R10 F3000\n"))
            .unwrap()
            .1;
        assert_eq!(ij.len(), r.len());
        assert!(ij.iter().zip(&r).all(|(a, b)| near(a.xy, b.xy)));
    }

    #[test]
    fn unknown_words_are_refused() {
        assert!(read_program("G1 X1 Z2\n").is_err());
        assert!(read_program("$130=200\n").is_err());
        assert!(read_program("G4 P0\nG21 G90 G17 G94\n")
            .unwrap()
            .1
            .is_empty());
    }
}
