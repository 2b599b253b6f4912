//! A job the web page can run: a G-code file as it is, or an SVG or a line of
//! text turned into G-code the way `cargo host svg` / `cargo host text` do it
//! (planned from where the pen is, parked at the origin). A job carries the lines
//! to send, the moves it draws (the preview, read back with the G-code reader)
//! and an estimate of each move's duration, so that progress along the path and
//! the time left can be told from where the machine reports the pen.

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
    /// `rapid` the rapid rate in mm/min (for the estimate).
    pub fn new(name: &str, src: Source, pen: Pt, rapid: f64) -> Result<Job> {
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
        let mut t = 0.0;
        let ends_s = moves
            .iter()
            .map(|m| {
                let rate = m.feed.unwrap_or(rapid).max(1.0) / 60.0;
                t += m.from.dist(m.to) / rate;
                t
            })
            .collect();
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
                [m.from.x, m.from.y, m.to.x, m.to.y, d]
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

    /// Estimated seconds of the job done when the pen is at `p`.
    pub fn update(&mut self, job: &Job, p: Pt) -> f64 {
        let end = (self.at + LOOK_AHEAD).min(job.moves.len());
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
        let job = Job::new("square", Source::Gcode(g), Pt::new(0.0, 0.0), 1200.0).unwrap();
        assert_eq!(job.lines.len(), 6);
        assert_eq!(job.moves.len(), 3);
        // 10 mm at 1200 mm/min (0.5 s), 10 mm at 600 (1 s), 14.1 mm at 1200.
        assert!((job.total_s() - (0.5 + 1.0 + 200f64.sqrt() / 20.0)).abs() < 1e-9);
        let mut t = Tracker::new();
        assert!((t.update(&job, Pt::new(5.0, 0.0)) - 0.25).abs() < 1e-9);
        assert!((t.update(&job, Pt::new(10.0, 5.0)) - 1.0).abs() < 1e-9);
        assert!((t.update(&job, Pt::new(0.0, 0.0)) - job.total_s()).abs() < 1e-9);
        assert_eq!(job.preview()[1], [10.0, 0.0, 10.0, 10.0, 1.0]);
    }

    #[test]
    fn text_and_svg_jobs_are_planned_and_parked() {
        let job = Job::new("t", Source::Text("一 Hi", 10.0), Pt::new(0.0, 0.0), 3000.0).unwrap();
        let last = job.moves.last().unwrap();
        assert_eq!((last.to, last.kind), (Pt::new(0.0, 0.0), MoveKind::Travel));
        assert!(job.moves.iter().any(|m| m.kind == MoveKind::Draw));
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="20mm" viewBox="0 0 20 20"><circle cx="10" cy="10" r="5"/><text id="t" x="1" y="19">Hi</text></svg>"#;
        let job = Job::new("c", Source::Svg(svg), Pt::new(0.0, 0.0), 3000.0).unwrap();
        // The circle's fill and the text are named as left out, on a 20 mm page.
        let names: Vec<&str> = job.left_out.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["(unnamed path)", "t \"Hi\""]);
        let (w, h) = job.page.unwrap();
        assert!((w - 20.0).abs() < 1e-4 && (h - 20.0).abs() < 1e-4);
        let only_text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="20mm"><text id="t">Hi</text></svg>"#;
        let Err(e) = Job::new("e", Source::Svg(only_text), Pt::new(0.0, 0.0), 3000.0) else {
            panic!("a job with nothing drawable")
        };
        assert!(
            e.to_string().contains("nothing drawable") && e.to_string().contains("text t"),
            "{e}"
        );
        assert!(Job::new("e", Source::Gcode("(nothing)\n"), Pt::new(0.0, 0.0), 3000.0).is_err());
        assert!(Job::new(
            "x",
            Source::Text("\u{1F600}", 10.0),
            Pt::new(0.0, 0.0),
            3000.0
        )
        .is_err());
    }
}
