//! A job the web page can run: a G-code file as it is, or an SVG or a line of
//! text turned into G-code the way `cargo host svg` / `cargo host text` do it
//! (planned from where the pen is, parked at the origin). A job carries the lines
//! to send, the moves it draws (the preview, read back with the G-code reader)
//! and an estimate of each move's duration, so that progress along the path and
//! the time left can be told from where the machine reports the pen.
//!
//! The estimate is the firmware's own ([`crate::estimate`]): the job run on a
//! virtual board with the machine's settings (its `$$`), from where the pen is,
//! each move's end found in the step stream. A model of the planner here read a
//! text job 9 % short; the firmware's code cannot disagree with itself.

use crate::gcode_out::{to_gcode, GcodeOptions};
use crate::geom::{Pt, Route};
use crate::plan::{plan, PlanOptions};
use crate::svg_in::{dist_to_segment, read_svg, LayerMode, Skipped, SvgOptions};
use crate::text::layout;
use crate::toolpath::{self, Move, MoveKind};
use anyhow::{bail, Result};
use inkstep_core::settings::Settings;
use inkstep_serial::stream::{prepare, Line};

/// What was uploaded.
pub enum Source<'a> {
    Gcode(&'a str),
    Svg(&'a str),
    /// Text and character box in mm.
    Text(&'a str, f64),
}

/// Moves up to which a job's estimate is computed while it loads (a tenth of
/// a second or so); bigger jobs get theirs afterwards.
pub const QUICK_MOVES: usize = 20_000;

/// The estimate of [`crate::estimate`], each move's end and the total; at the
/// end of the last move the job is done (what follows, the program's end,
/// takes a few milliseconds).
fn firmware_estimate(gcode: &str, settings: &Settings, pen: Pt, moves: &[Move]) -> (Vec<f64>, f64) {
    let est = crate::estimate::estimate(gcode, settings, pen, moves);
    let (mut ends_s, total) = (est.ends_s, est.job_s);
    if let Some(l) = ends_s.last_mut() {
        *l = l.max(total);
    }
    (ends_s, total)
}

pub struct Job {
    /// Unique among the jobs built (the late estimate finds its job by it).
    pub id: u64,
    pub name: String,
    pub lines: Vec<Line>,
    pub moves: Vec<Move>,
    /// Estimated seconds from the job's start to the end of each move.
    pub ends_s: Vec<f64>,
    /// Estimated seconds for the whole job (to the end of the program).
    pub total: f64,
    /// The preview's rows ([`Job::preview`]) in pieces of at most
    /// [`super::link::CHUNK`] rows, five little-endian `f32` a row (x0, y0, x1, y1, drawn), made while
    /// the job is built.
    pub preview_bin: Vec<Vec<u8>>,
    /// The estimate is the firmware's; false while a big job's is computed
    /// (then a rough one, moves at their feed, stands in).
    pub estimated: bool,
    /// What an SVG holds that the job does not draw (text, images, fills).
    pub left_out: Vec<Skipped>,
    /// An SVG's page size (mm).
    pub page: Option<(f64, f64)>,
}

/// Largest line Grbl takes (its receive buffer).
const RX: usize = 128;

impl Job {
    /// Builds a job; `pen` is where the pen is now (the plan starts there) and
    /// `settings` the machine's, for the estimate.
    pub fn new(name: &str, src: Source, pen: Pt, settings: &Settings) -> Result<Job> {
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
        // The lines to send on one core, the moves and their preview on the
        // other: a 10 MB file spends most of its load here.
        let (lines, moves, preview_bin) = std::thread::scope(|sc| {
            let lines = sc.spawn(|| prepare(&gcode, RX));
            let moves = toolpath::parse(&gcode);
            let rows = moves.as_deref().map(preview_rows).unwrap_or_default();
            (lines.join(), moves, rows)
        });
        let lines = lines
            .map_err(|_| anyhow::anyhow!("reading the lines failed"))?
            .map_err(anyhow::Error::msg)?;
        if lines.is_empty() {
            bail!("nothing to run");
        }
        let moves = moves?;
        // Small jobs get the firmware's estimate now; a big one (seconds of
        // simulation) a rough one, until `estimate` is run away from the load.
        let (ends_s, total, estimated) = if moves.len() <= QUICK_MOVES {
            let (e, t) = firmware_estimate(&gcode, settings, pen, &moves);
            (e, t, true)
        } else {
            let mut t = 0.0;
            let e: Vec<f64> = moves
                .iter()
                .map(|m| {
                    t += m.from.dist(m.to) / (m.feed.unwrap_or(3000.0).max(1.0) / 60.0);
                    t
                })
                .collect();
            (e, t, false)
        };
        static IDS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        let id = IDS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(Job {
            id,
            estimated,
            preview_bin,
            name: name.to_string(),
            lines,
            moves,
            ends_s,
            total,
            left_out,
            page,
        })
    }

    /// The firmware's estimate of this job (what `estimated` jobs have
    /// already): each move's end and the total, seconds.
    pub fn estimate(&self, settings: &Settings, pen: Pt) -> (Vec<f64>, f64) {
        let g: String = self.lines.iter().map(|l| l.text.clone() + "\n").collect();
        firmware_estimate(&g, settings, pen, &self.moves)
    }

    /// Estimated duration, s.
    pub fn total_s(&self) -> f64 {
        self.total
    }

    /// The moves as [x0, y0, x1, y1, drawn] rows for the page.
    pub fn preview(&self) -> Vec<[f64; 5]> {
        self.moves.iter().map(preview_row).collect()
    }
}

fn preview_row(m: &Move) -> [f64; 5] {
    let d = if m.kind == MoveKind::Draw { 1.0 } else { 0.0 };
    // Micrometres are plenty for a drawing, and keep the message short.
    let r = |v: f64| (v * 1000.0).round() / 1000.0;
    [r(m.from.x), r(m.from.y), r(m.to.x), r(m.to.y), d]
}

/// The preview rows in binary, [`super::link::CHUNK`] rows a piece: each row
/// five little-endian `f32` (x0, y0, x1, y1, drawn 0 or 1), 20 bytes. As JSON a
/// 10 MB job's half a million rows made 31 MB of text that took the server a
/// quarter of a second to write and the browser longer to read; as numbers the page
/// reads them with one typed-array view. `f32` keeps 0.01 mm up to 100 m.
fn preview_rows(moves: &[Move]) -> Vec<Vec<u8>> {
    moves
        .chunks(super::link::CHUNK)
        .map(preview_bytes)
        .collect()
}

/// One piece of [`preview_rows`].
fn preview_bytes(moves: &[Move]) -> Vec<u8> {
    let mut out = Vec::with_capacity(moves.len() * 20);
    for m in moves {
        for v in preview_row(m) {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    out
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

    /// A tracker for a job resumed at move `k`.
    pub fn starting_at(k: usize) -> Tracker {
        Tracker { at: k }
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
        let m = Settings::default();
        let job = Job::new("square", Source::Gcode(g), Pt::new(0.0, 0.0), &m).unwrap();
        assert_eq!(job.lines.len(), 6);
        assert_eq!(job.moves.len(), 3);
        // Each move's end in order, the draw (10 mm at 600 mm/min, after the
        // pen drop) at least a second, the program's end last.
        let e = &job.ends_s;
        assert!(e.windows(2).all(|w| w[0] < w[1]), "{e:?}");
        assert!(
            e[1] - e[0] > 1.0 && *e.last().unwrap() <= job.total_s(),
            "{e:?}"
        );
        let mut t = Tracker::new();
        let all = job.lines.len();
        let half = t.update(&job, Pt::new(10.0, 5.0), all);
        assert!((half - (e[0] + e[1]) / 2.0).abs() < 1e-9, "{half}");
        assert!((t.update(&job, Pt::new(0.0, 0.0), all) - e[2]).abs() < 1e-9);
        assert_eq!(job.preview()[1], [10.0, 0.0, 10.0, 10.0, 1.0]);
    }

    #[test]
    fn the_estimate_counts_the_pen_with_the_machines_settings() {
        let pen = "G0 X10\nM3\nG1 X20 F600\nM5\nG0 X0\n";
        let servo = |ms: f32| {
            let mut s = Settings::default();
            s.set(201, 1.0).unwrap();
            s.set(204, ms).unwrap();
            s.set(207, ms).unwrap();
            Job::new("p", Source::Gcode(pen), Pt::new(0.0, 0.0), &s)
                .unwrap()
                .total_s()
        };
        // A lift and a drop, waiting $204 and $207.
        let d = servo(600.0) - servo(100.0);
        assert!((d - 1.0).abs() < 0.01, "{d}");
    }

    #[test]
    fn a_job_parked_where_it_starts_is_not_done_at_its_start() {
        let m = Settings::default();
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
        let m = Settings::default();
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
