//! A job the web page can run: a G-code file as it is, or an SVG or a line of
//! text turned into G-code the way `cargo host svg` / `cargo host text` do it
//! (planned from where the pen is, parked at the origin). A job carries the lines
//! to send, the moves it draws (the preview, read back with the G-code reader)
//! and an estimate of each move's duration, so that progress along the path and
//! the time left can be told from where the machine reports the pen.
//!
//! The estimate follows the machine's own rules (from its settings): each move
//! at its feed (or the rapid rate) within the axes' rates and accelerations,
//! corners taken at the speed the junction deviation ($11) allows, a full stop
//! at every pen change, and the pen's own time: the lift/drop wait ($204) of a
//! servo pen, or the Z move between $205 and $206 of a Z pen. Text is mostly
//! short strokes and pen changes, so leaving those out (as a plain length /
//! feed sum does) made a 27 s job read 8 s.

use crate::gcode_out::{to_gcode, GcodeOptions};
use crate::geom::{Pt, Route};
use crate::plan::{plan, PlanOptions};
use crate::svg_in::{dist_to_segment, read_svg, LayerMode, Skipped, SvgOptions};
use crate::text::layout;
use crate::toolpath::{self, Move, MoveKind};
use anyhow::{bail, Result};
use inkstep_serial::stream::{prepare, Line};

/// What was uploaded.
pub enum Source<'a> {
    Gcode(&'a str),
    Svg(&'a str),
    /// Text and character box in mm.
    Text(&'a str, f64),
}

/// What the estimate needs from the machine's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Machine {
    /// Axis maximum rates ($110..$112), mm/min.
    pub rate: [f64; 3],
    /// Axis accelerations ($120..$122), mm/s^2.
    pub accel: [f64; 3],
    /// Junction deviation ($11), mm.
    pub junction: f64,
    /// Servo pen ($201 = 1): lift/drop wait ($204), s. None: a Z pen.
    pub servo_s: Option<f64>,
    /// Z pen travel |$205 - $206|, mm.
    pub z_travel: f64,
}

impl Default for Machine {
    /// The firmware's defaults.
    fn default() -> Machine {
        Machine::from_settings(|_| None)
    }
}

impl Machine {
    /// From the settings `get` knows (the firmware's defaults for the rest).
    pub fn from_settings(get: impl Fn(u16) -> Option<f64>) -> Machine {
        let v = |n: u16| {
            get(n)
                .filter(|v| v.is_finite())
                .or_else(|| {
                    inkstep_core::settings::TABLE
                        .iter()
                        .find(|d| d.number == n)
                        .map(|d| d.default as f64)
                })
                .unwrap_or(0.0)
        };
        Machine {
            rate: [v(110), v(111), v(112)].map(|r| r.max(1.0)),
            accel: [v(120), v(121), v(122)].map(|a| a.max(0.1)),
            junction: v(11).max(0.0),
            servo_s: (v(201) == 1.0).then(|| v(204) / 1000.0),
            z_travel: (v(205) - v(206)).abs(),
        }
    }

    /// This machine with settings `set` changed.
    pub fn with(&self, set: &[(u16, f64)]) -> Machine {
        let mut m = *self;
        for &(n, v) in set {
            match n {
                110..=112 => m.rate[usize::from(n - 110)] = v.max(1.0),
                120..=122 => m.accel[usize::from(n - 120)] = v.max(0.1),
                11 => m.junction = v.max(0.0),
                201 if v == 1.0 => m.servo_s = Some(m.servo_s.unwrap_or(0.15)),
                201 => m.servo_s = None,
                204 => m.servo_s = m.servo_s.map(|_| v / 1000.0),
                _ => {}
            }
        }
        m
    }

    /// The slowest of the X and Y rates (the page's older rapid figure).
    pub fn rapid(&self) -> f64 {
        self.rate[0].min(self.rate[1])
    }

    /// Seconds a pen lift or drop takes.
    pub fn pen_s(&self) -> f64 {
        match self.servo_s {
            Some(s) => s,
            None => trapezoid(self.z_travel, self.rate[2] / 60.0, self.accel[2], 0.0, 0.0),
        }
    }
}

/// Seconds to go `len` mm, entering at `vi` and leaving at `vo` mm/s, at most
/// `v` mm/s, accelerating and braking at `a` mm/s^2.
fn trapezoid(len: f64, v: f64, a: f64, vi: f64, vo: f64) -> f64 {
    if len <= 0.0 {
        return 0.0;
    }
    let up = (v * v - vi * vi).max(0.0) / (2.0 * a);
    let down = (v * v - vo * vo).max(0.0) / (2.0 * a);
    if up + down <= len {
        (v - vi).max(0.0) / a + (v - vo).max(0.0) / a + (len - up - down) / v
    } else {
        let peak = ((2.0 * a * len + vi * vi + vo * vo) / 2.0).sqrt();
        (peak - vi).max(0.0) / a + (peak - vo).max(0.0) / a
    }
}

/// Estimated seconds from the start to the end of each move.
pub fn estimate(moves: &[Move], m: &Machine) -> Vec<f64> {
    let n = moves.len();
    // Per move: length, unit direction, top speed and acceleration (mm/s, mm/s^2)
    // as the axes it uses allow.
    let mut len = vec![0.0; n];
    let mut dir = vec![(0.0, 0.0); n];
    let mut top = vec![0.0; n];
    let mut acc = vec![0.0; n];
    for (i, mv) in moves.iter().enumerate() {
        let (dx, dy) = (mv.to.x - mv.from.x, mv.to.y - mv.from.y);
        let l = dx.hypot(dy);
        len[i] = l;
        if l <= 0.0 {
            continue;
        }
        let (ux, uy) = (dx / l, dy / l);
        dir[i] = (ux, uy);
        let lim = |per_axis: [f64; 3]| {
            let mut best = f64::INFINITY;
            for (u, p) in [(ux, per_axis[0]), (uy, per_axis[1])] {
                if u.abs() > 1e-12 {
                    best = best.min(p / u.abs());
                }
            }
            best
        };
        let wanted = mv.feed.unwrap_or(f64::INFINITY).max(1.0) / 60.0;
        top[i] = wanted.min(lim(m.rate.map(|r| r / 60.0)));
        acc[i] = lim(m.accel);
    }
    // A stop before move i: the first move, and every pen change.
    let stop_before = |i: usize| i == 0 || moves[i].kind != moves[i - 1].kind;
    // Highest speed at the start of each move (the junction with the one before).
    let mut entry = vec![0.0; n + 1];
    for i in 1..n {
        if stop_before(i) || len[i] <= 0.0 || len[i - 1] <= 0.0 {
            continue;
        }
        let (a, b) = (dir[i - 1], dir[i]);
        let cos = -(a.0 * b.0 + a.1 * b.1);
        let cap = top[i].min(top[i - 1]);
        entry[i] = if cos < -0.999_999 {
            cap
        } else {
            let sin_half = (0.5 * (1.0 - cos)).max(0.0).sqrt();
            let a_j = acc[i].min(acc[i - 1]);
            let v2 = a_j * m.junction * sin_half / (1.0 - sin_half).max(1e-9);
            v2.sqrt().min(cap)
        };
    }
    // Backward: each move can brake from its entry to the next one's.
    for i in (0..n).rev() {
        let next = if i + 1 < n && !stop_before(i + 1) {
            entry[i + 1]
        } else {
            0.0
        };
        entry[i] = entry[i].min((next * next + 2.0 * acc[i] * len[i]).sqrt());
    }
    // Forward: each move can reach its exit from its entry.
    let mut t = 0.0;
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        if i > 0 && stop_before(i) {
            t += m.pen_s();
        }
        let vi = entry[i];
        let mut vo = if i + 1 < n && !stop_before(i + 1) {
            entry[i + 1]
        } else {
            0.0
        };
        if len[i] > 0.0 {
            vo = vo.min((vi * vi + 2.0 * acc[i] * len[i]).sqrt());
            if i + 1 < n {
                entry[i + 1] = entry[i + 1].min(vo);
            }
            t += trapezoid(len[i], top[i], acc[i], vi, vo);
        }
        out.push(t);
    }
    out
}

pub struct Job {
    pub name: String,
    pub lines: Vec<Line>,
    pub moves: Vec<Move>,
    /// Estimated seconds from the job's start to the end of each move.
    pub ends_s: Vec<f64>,
    /// What an SVG holds that the job does not draw (text, images, fills).
    pub left_out: Vec<Skipped>,
    /// An SVG's page size (mm).
    pub page: Option<(f64, f64)>,
}

/// Largest line Grbl takes (its receive buffer).
const RX: usize = 128;

impl Job {
    /// Builds a job; `pen` is where the pen is now (the plan starts there) and
    /// `machine` what the estimate needs of the settings.
    pub fn new(name: &str, src: Source, pen: Pt, machine: &Machine) -> Result<Job> {
        let route = Route {
            start: pen,
            park: Some(Pt::new(0.0, 0.0)),
        };
        let planned = |strokes: Vec<_>| {
            let s = plan(&strokes, route, &PlanOptions::default());
            to_gcode(
                &s,
                &GcodeOptions {
                    route,
                    ..GcodeOptions::default()
                },
            )
        };
        let (mut left_out, mut page) = (Vec::new(), None);
        let gcode = match src {
            Source::Gcode(g) => g.to_string(),
            Source::Svg(svg) => {
                // One pass: the pen changes of layers need M6, which the
                // firmware does not take yet.
                let d = read_svg(
                    svg.as_bytes(),
                    &SvgOptions {
                        layers: LayerMode::None,
                        ..SvgOptions::default()
                    },
                )?;
                let strokes = d.strokes();
                if strokes.is_empty() {
                    let what: Vec<String> = d
                        .skipped
                        .iter()
                        .map(|s| format!("{} {}", s.kind.label(), s.name))
                        .collect();
                    bail!("nothing drawable in the SVG ({})", what.join(", "));
                }
                left_out = d.skipped;
                page = Some(d.page);
                planned(strokes)
            }
            Source::Text(text, size) => {
                if !(size > 0.5 && size < 500.0) {
                    bail!("character size {size} mm: choose 0.5 to 500");
                }
                planned(layout(text, size, "futural")?.strokes)
            }
        };
        let lines = prepare(&gcode, RX).map_err(anyhow::Error::msg)?;
        if lines.is_empty() {
            bail!("nothing to run");
        }
        let moves = toolpath::parse(&gcode)?;
        // Settings the job itself makes ($120=500) count for its estimate.
        let set: Vec<(u16, f64)> = lines
            .iter()
            .filter_map(|l| {
                let (n, v) = l.text.strip_prefix('$')?.split_once('=')?;
                Some((n.parse().ok()?, v.parse().ok()?))
            })
            .collect();
        let machine = if set.is_empty() {
            *machine
        } else {
            machine.with(&set)
        };
        let ends_s = estimate(&moves, &machine);
        Ok(Job {
            name: name.to_string(),
            lines,
            moves,
            ends_s,
            left_out,
            page,
        })
    }

    /// Estimated duration, s.
    pub fn total_s(&self) -> f64 {
        self.ends_s.last().copied().unwrap_or(0.0)
    }

    /// The moves as [x0, y0, x1, y1, drawn] rows for the page.
    pub fn preview(&self) -> Vec<[f64; 5]> {
        self.moves
            .iter()
            .map(|m| {
                let d = if m.kind == MoveKind::Draw { 1.0 } else { 0.0 };
                // Micrometres are plenty for a drawing, and keep the message short.
                let r = |v: f64| (v * 1000.0).round() / 1000.0;
                [r(m.from.x), r(m.from.y), r(m.to.x), r(m.to.y), d]
            })
            .collect()
    }
}

/// Follows a running job along its moves from the positions the machine
/// reports: the move nearest the pen, searched a little ahead of the last one
/// (a path may cross itself, so never backwards and never far).
pub struct Tracker {
    at: usize,
}

/// Moves searched ahead of the current one.
const LOOK_AHEAD: usize = 400;

impl Tracker {
    pub fn new() -> Tracker {
        Tracker { at: 0 }
    }

    /// The move the pen is on now.
    pub fn at(&self) -> usize {
        self.at
    }

    /// Estimated seconds of the job done when the pen is at `p`, `sent` of
    /// the job's lines having gone to the machine: it cannot be on a move of a
    /// line not sent yet, which keeps a job that starts and ends at the same
    /// place (a text parked at the origin) from reading as done at its start.
    pub fn update(&mut self, job: &Job, p: Pt, sent: usize) -> f64 {
        let last_line = match sent.checked_sub(1) {
            Some(k) => job.lines.get(k).map_or(usize::MAX, |l| l.file_line),
            None => 0,
        };
        let sent = job.moves.partition_point(|m| m.line <= last_line);
        let end = (self.at + LOOK_AHEAD)
            .min(sent.max(self.at + 1))
            .min(job.moves.len());
        let near = (self.at..end).min_by(|&a, &b| {
            let da = dist_to_segment(p, job.moves[a].from, job.moves[a].to);
            let db = dist_to_segment(p, job.moves[b].from, job.moves[b].to);
            // Ties (a point on two moves) go to the earlier one.
            da.total_cmp(&db).then(a.cmp(&b))
        });
        let Some(k) = near else {
            return job.total_s();
        };
        self.at = k;
        let m = &job.moves[k];
        let len = m.from.dist(m.to);
        let frac = if len > 0.0 {
            (m.from.dist(p) / len).min(1.0)
        } else {
            1.0
        };
        let start = if k == 0 { 0.0 } else { job.ends_s[k - 1] };
        start + frac * (job.ends_s[k] - start)
    }
}

impl Default for Tracker {
    fn default() -> Self {
        Tracker::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gcode_job_estimates_its_time_and_tracks_the_pen() {
        let g = "G21 G90\nG0 X10\nM3\nG1 X10 Y10 F600\nM5\nG0 X0 Y0\n";
        // Near-instant acceleration and pen: the times are length / rate.
        let quick = Machine {
            rate: [1200.0, 1200.0, 600.0],
            accel: [1e9; 3],
            junction: 0.01,
            servo_s: Some(0.0),
            z_travel: 2.0,
        };
        let job = Job::new("square", Source::Gcode(g), Pt::new(0.0, 0.0), &quick).unwrap();
        assert_eq!(job.lines.len(), 6);
        assert_eq!(job.moves.len(), 3);
        // 10 mm at 1200 mm/min (0.5 s), 10 mm at 600 (1 s), and the rapid
        // diagonal back with both axes at 1200 mm/min: 10 mm each, 0.5 s.
        assert!((job.total_s() - 2.0).abs() < 1e-6, "{}", job.total_s());
        let mut t = Tracker::new();
        let all = job.lines.len();
        assert!((t.update(&job, Pt::new(5.0, 0.0), all) - 0.25).abs() < 1e-6);
        assert!((t.update(&job, Pt::new(10.0, 5.0), all) - 1.0).abs() < 1e-6);
        assert!((t.update(&job, Pt::new(0.0, 0.0), all) - job.total_s()).abs() < 1e-6);
        assert_eq!(job.preview()[1], [10.0, 0.0, 10.0, 10.0, 1.0]);
    }

    #[test]
    fn the_estimate_counts_acceleration_corners_and_the_pen() {
        let m = Machine::default();
        // 100 mm at 3000 mm/min (50 mm/s) with 200 mm/s^2: 0.25 s up, 0.25 s
        // down (6.25 mm each), 87.5 mm at speed (1.75 s).
        let line = Job::new("l", Source::Gcode("G0 X100\n"), Pt::new(0.0, 0.0), &m).unwrap();
        assert!((line.total_s() - 2.25).abs() < 1e-9, "{}", line.total_s());
        // Straight on through a split: no stop in between.
        let split = Job::new(
            "s",
            Source::Gcode("G0 X50\nG0 X100\n"),
            Pt::new(0.0, 0.0),
            &m,
        )
        .unwrap();
        assert!((split.total_s() - 2.25).abs() < 1e-6, "{}", split.total_s());
        // A reversal stops.
        let back = Job::new("b", Source::Gcode("G0 X50\nG0 X0\n"), Pt::new(0.0, 0.0), &m).unwrap();
        assert!((back.total_s() - 2.0 * (0.5 + 37.5 / 50.0)).abs() < 1e-6);
        // Pen changes: a servo waits $204 each time; a Z pen moves.
        let pen = "G0 X10\nM3\nG1 X20 F600\nM5\nG0 X0\n";
        let servo = Machine {
            servo_s: Some(0.5),
            ..m
        };
        let a = Job::new("p", Source::Gcode(pen), Pt::new(0.0, 0.0), &m).unwrap();
        let b = Job::new("p", Source::Gcode(pen), Pt::new(0.0, 0.0), &servo).unwrap();
        assert!((b.total_s() - a.total_s() - 2.0 * (0.5 - m.pen_s())).abs() < 1e-9);
        // Z pen: 2 mm at 600 mm/min (10 mm/s) with 100 mm/s^2: 0.1 s up, 0.1 s down.
        assert!((m.pen_s() - 0.3).abs() < 1e-9, "{}", m.pen_s());
    }

    #[test]
    fn a_job_parked_where_it_starts_is_not_done_at_its_start() {
        let m = Machine::default();
        let job = Job::new("t", Source::Text("Hi", 10.0), Pt::new(0.0, 0.0), &m).unwrap();
        let park = *job.moves.last().unwrap();
        assert!(job.moves.len() < 400 && park.to == Pt::new(0.0, 0.0));
        // The park runs back across the whole text: a pen early in the job
        // may be nearest to it. With the first lines sent, it is still early.
        let q = Pt::new(
            park.from.x + 0.7 * (park.to.x - park.from.x),
            park.from.y + 0.7 * (park.to.y - park.from.y),
        );
        let mut t = Tracker::new();
        assert!(t.update(&job, q, 5) < 0.3 * job.total_s());
        // All answered, back at the origin: done.
        let mut t = Tracker::new();
        for k in 0..job.moves.len() {
            let mv = &job.moves[k];
            t.update(&job, mv.to, job.lines.len());
        }
        assert!((t.update(&job, Pt::new(0.0, 0.0), job.lines.len()) - job.total_s()).abs() < 1e-6);
    }

    #[test]
    fn text_and_svg_jobs_are_planned_and_parked() {
        let m = Machine::default();
        let job = Job::new("t", Source::Text("一 Hi", 10.0), Pt::new(0.0, 0.0), &m).unwrap();
        let last = job.moves.last().unwrap();
        assert_eq!((last.to, last.kind), (Pt::new(0.0, 0.0), MoveKind::Travel));
        assert!(job.moves.iter().any(|m| m.kind == MoveKind::Draw));
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="20mm" viewBox="0 0 20 20"><circle cx="10" cy="10" r="5"/><text id="t" x="1" y="19">Hi</text></svg>"#;
        let job = Job::new("c", Source::Svg(svg), Pt::new(0.0, 0.0), &m).unwrap();
        // The circle's fill and the text are named as left out, on a 20 mm page.
        let names: Vec<&str> = job.left_out.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["(unnamed path)", "t \"Hi\""]);
        let (w, h) = job.page.unwrap();
        assert!((w - 20.0).abs() < 1e-4 && (h - 20.0).abs() < 1e-4);
        let only_text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="20mm"><text id="t">Hi</text></svg>"#;
        let Err(e) = Job::new("e", Source::Svg(only_text), Pt::new(0.0, 0.0), &m) else {
            panic!("a job with nothing drawable")
        };
        assert!(
            e.to_string().contains("nothing drawable") && e.to_string().contains("text t"),
            "{e}"
        );
        assert!(Job::new("e", Source::Gcode("(nothing)\n"), Pt::new(0.0, 0.0), &m).is_err());
        assert!(Job::new("x", Source::Text("\u{1F600}", 10.0), Pt::new(0.0, 0.0), &m).is_err());
    }
}
