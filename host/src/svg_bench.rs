//! The large-drawing benchmark (`cargo host svg-bench`): how long a big SVG
//! takes from text to G-code, stage by stage. The drawing is generated (a
//! seeded scatter of short curved paths on an A4-ish page, ~110 bytes each,
//! so 179,000 paths make 20 MB, like the file that once planned for more
//! than 15 minutes), never stored. The goal is a whole run under a minute;
//! the benchmark fails above it.

use crate::gcode_out::{to_gcode, GcodeOptions};
use crate::geom::{pen_up_travel, Pt, Route};
use crate::plan::{plan, PlanOptions};
use crate::svg_in::{read_svg, LayerMode, SvgOptions};
use anyhow::{bail, Result};
use std::fmt::Write as _;
use std::time::Instant;

/// Goal for the whole run (read, plan, write), s.
pub const GOAL_S: f64 = 60.0;

/// A seeded SVG of `n` short paths (a cubic and a line each), mm units.
pub fn drawing(n: usize, seed: u64) -> String {
    let mut s = seed | 1;
    let mut rnd = |lo: f64, hi: f64| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut out = String::from(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="280mm" height="190mm" viewBox="0 0 280 190">"#,
    );
    for _ in 0..n {
        let _ = write!(
            out,
            "\n<path d=\"M {:.3} {:.3} c {:.3} {:.3} {:.3} {:.3} {:.3} {:.3} l {:.3} {:.3}\" fill=\"none\" stroke=\"black\"/>",
            rnd(8.0, 272.0),
            rnd(8.0, 182.0),
            rnd(-3.0, 3.0),
            rnd(-3.0, 3.0),
            rnd(-3.0, 3.0),
            rnd(-3.0, 3.0),
            rnd(-5.0, 5.0),
            rnd(-5.0, 5.0),
            rnd(-2.0, 2.0),
            rnd(-2.0, 2.0),
        );
    }
    out.push_str("\n</svg>\n");
    out
}

pub struct Figures {
    pub bytes: usize,
    pub paths: usize,
    pub read_s: f64,
    pub plan_s: f64,
    pub write_s: f64,
    pub lines: usize,
    pub travel_before: f64,
    pub travel_after: f64,
}

impl Figures {
    pub fn total_s(&self) -> f64 {
        self.read_s + self.plan_s + self.write_s
    }
}

/// Runs the pipeline on a generated drawing of `n` paths, as `cargo host svg`
/// with its defaults does.
pub fn run(n: usize, progress: bool) -> Result<Figures> {
    let svg = drawing(n, 0x5EED);
    let t = Instant::now();
    let d = read_svg(
        svg.as_bytes(),
        &SvgOptions {
            layers: LayerMode::None,
            ..SvgOptions::default()
        },
    )?;
    let strokes = d.strokes();
    let read_s = t.elapsed().as_secs_f64();
    let route = Route::closed(Pt::new(0.0, 0.0));
    let t = Instant::now();
    let planned = plan(
        &strokes,
        route,
        &PlanOptions {
            progress,
            ..PlanOptions::default()
        },
    );
    let plan_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let g = to_gcode(
        &planned,
        &GcodeOptions {
            route,
            ..GcodeOptions::default()
        },
    );
    let write_s = t.elapsed().as_secs_f64();
    if strokes.len() != n {
        bail!("{} strokes read from {n} paths", strokes.len());
    }
    Ok(Figures {
        bytes: svg.len(),
        paths: n,
        read_s,
        plan_s,
        write_s,
        lines: g.lines().count(),
        travel_before: pen_up_travel(&strokes, route),
        travel_after: pen_up_travel(&planned, route),
    })
}
