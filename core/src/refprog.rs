//! Reader for the motion benchmark's reference programs (`bench/*.nc`): the `$`
//! settings they start with and G0-G3 moves with X, Y, Z, I, J, F in G21/G90. Used by
//! the benchmark test and the interrupt-cost harness so both run the same moves.
//!
//! Deliberately tiny and not the product's G-code interpreter (that belongs to the
//! protocol module): no modal groups beyond the motion mode, no units or offsets.
//! Lines become [`Path::LineFine`] with their exact end points in 1/256 step, arcs
//! [`Path::Arc`] with the centre rounded to a step. No allocation.

use crate::motion::{Feed, Move, Path};
use crate::planner::PlannerConfig;

/// Streams the moves of a program.
#[derive(Clone, Debug)]
pub struct RefProgram<'a> {
    lines: core::str::Lines<'a>,
    cfg: PlannerConfig,
    pos: [f64; 3],
    feed: f32,
    motion: u8,
    count: u32,
}

impl<'a> RefProgram<'a> {
    /// Reads the settings at the head of `text` into `base`.
    pub fn new(text: &'a str, base: PlannerConfig) -> Self {
        let mut cfg = base;
        for line in text.lines() {
            let Some(rest) = line.trim().strip_prefix('$') else {
                continue;
            };
            let Some((k, v)) = rest.split_once('=') else {
                continue;
            };
            let Ok(v) = v.trim().parse::<f32>() else {
                continue;
            };
            let axis = |k: &str| {
                k.as_bytes()
                    .get(2)
                    .map(|b| usize::from(b.wrapping_sub(b'0')))
            };
            match (k.get(..2), axis(k)) {
                (Some("10"), Some(a)) if a < 3 => cfg.axes[a].steps_per_mm = v,
                (Some("11"), Some(a)) if a < 3 => cfg.axes[a].max_rate = v,
                (Some("12"), Some(a)) if a < 3 => cfg.axes[a].accel = v,
                _ if k == "11" => cfg.junction_deviation = v,
                _ => {}
            }
        }
        RefProgram {
            lines: text.lines(),
            cfg,
            pos: [0.0; 3],
            feed: 0.0,
            motion: 0,
            count: 0,
        }
    }

    /// The settings the program asks for.
    pub fn config(&self) -> PlannerConfig {
        self.cfg
    }

    fn q8(&self, mm: f64, axis: usize) -> i32 {
        libm::round(mm * f64::from(self.cfg.axes[axis].steps_per_mm) * 256.0) as i32
    }
    fn steps(&self, mm: f64, axis: usize) -> i32 {
        libm::round(f64::from(self.q8(mm, axis)) / 256.0) as i32
    }
}

impl Iterator for RefProgram<'_> {
    type Item = Move;

    fn next(&mut self) -> Option<Move> {
        loop {
            let line = self.lines.next()?.trim();
            if line.starts_with('$') || line.is_empty() {
                continue;
            }
            let mut target = self.pos;
            let mut ij = [0.0f64; 2];
            let mut has_axis = false;
            let mut dwell = false;
            let mut rest = line;
            while let Some(c) = rest.chars().next() {
                let letter = c.to_ascii_uppercase();
                let body = &rest[c.len_utf8()..];
                let end = body
                    .find(|ch: char| !(ch.is_ascii_digit() || ch == '.' || ch == '-' || ch == '+'))
                    .unwrap_or(body.len());
                let num: f64 = body[..end].parse().unwrap_or(f64::NAN);
                rest = body[end..].trim_start();
                match letter {
                    'G' if num == 4.0 => dwell = true,
                    'G' if (0.0..=3.0).contains(&num) => self.motion = num as u8,
                    'X' => (target[0], has_axis) = (num, true),
                    'Y' => (target[1], has_axis) = (num, true),
                    'Z' => (target[2], has_axis) = (num, true),
                    'I' => ij[0] = num,
                    'J' => ij[1] = num,
                    'F' => self.feed = num as f32,
                    _ => {}
                }
            }
            if !has_axis || dwell || target.iter().any(|v| !v.is_finite()) {
                continue;
            }
            let t = [
                self.steps(target[0], 0),
                self.steps(target[1], 1),
                self.steps(target[2], 2),
            ];
            let path = match self.motion {
                2 | 3 => Path::Arc {
                    center: [self.steps(ij[0], 0), self.steps(ij[1], 1)],
                    ccw: self.motion == 3,
                    turns: 0,
                },
                _ if target[2] == self.pos[2] => Path::LineFine {
                    from: [self.q8(self.pos[0], 0), self.q8(self.pos[1], 1)],
                    to: [self.q8(target[0], 0), self.q8(target[1], 1)],
                },
                _ => Path::Line,
            };
            let feed = if self.motion == 0 {
                Feed::Rapid
            } else {
                Feed::MmPerMin(self.feed)
            };
            self.pos = target;
            self.count += 1;
            return Some(Move {
                target: t,
                path,
                feed,
                line: self.count,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_settings_lines_and_arcs() {
        let text = "$100=100\n$111=6000\n$121=250\n$11=0.02\nG21 G90\nG1 X1.5 Y-2 F1200\nG4 P0\nG2 X0 Y0 I-1.5 J2\nG0 Z3\n";
        let mut p = RefProgram::new(text, PlannerConfig::default());
        let c = p.config();
        assert_eq!(c.axes[0].steps_per_mm, 100.0);
        assert_eq!(c.axes[1].max_rate, 6000.0);
        assert_eq!(c.axes[1].accel, 250.0);
        assert_eq!(c.junction_deviation, 0.02);
        let m1 = p.next().unwrap();
        assert_eq!(m1.target, [150, -160, 0]);
        assert_eq!(
            m1.path,
            Path::LineFine {
                from: [0, 0],
                to: [150 * 256, -160 * 256]
            }
        );
        assert_eq!(m1.feed, Feed::MmPerMin(1200.0));
        let m2 = p.next().unwrap();
        assert_eq!(
            m2.path,
            Path::Arc {
                center: [-150, 160],
                ccw: false,
                turns: 0
            }
        );
        assert_eq!(m2.target, [0, 0, 0]);
        let m3 = p.next().unwrap();
        assert_eq!(
            (m3.path, m3.feed, m3.target),
            (Path::Line, Feed::Rapid, [0, 0, 240])
        );
        assert!(p.next().is_none());
    }
}
