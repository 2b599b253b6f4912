//! The planning benchmark (`cargo host plan-bench`): the pen-up travel of the
//! route the machine really drives, on the work the user runs.
//!
//! Each text is laid out as `cargo host text` lays it out (20 mm boxes), the
//! pen starts at the origin and the program parks it there (the command's
//! defaults), and every method's stroke order goes through the same G-code
//! writer. The travel is then read back from that G-code with the G-code reader
//! (every G0 and pen-up move, the park included), never recomputed from strokes.
//! vpype's `linesort` and `linesort --two-opt` get the strokes in shuffled
//! orders (so that vpype is not handed our order or the writing order; it
//! starts from the first stroke it gets, so the best of three shuffles counts);
//! their output SVG is read back and written as G-code with the same start and
//! park.

use crate::gcode_out::{to_gcode, GcodeOptions};
use crate::geom::{Pt, Route, Stroke};
use crate::plan::{self, order::Problem, PlanOptions};
use crate::svg_in::{strokes_from_svg, MM_PER_PX};
use crate::text::layout;
use crate::toolpath;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::process::Command;
use std::time::Instant;

/// The benchmark texts: two lines of hanzi and one Latin line.
pub const TEXTS: [&str; 3] = [
    "一帆风顺中国地质大学写字机器人",
    "天地玄黄宇宙洪荒日月盈昃辰宿列张",
    "The quick brown fox jumps over the lazy dog",
];

/// Character box in mm (`cargo host text`'s default).
pub const SIZE_MM: f64 = 20.0;

/// Seeds of the shuffled orders vpype is given (its best result counts).
pub const SHUFFLES: [u64; 3] = [1, 2, 3];

/// Goal: inkstep's route at most this fraction of vpype's best.
pub const GOAL: f64 = 0.85;

/// vpype 1.15's best pen-up travel (mm, from `linesort` and `linesort
/// --two-opt`) on each of [`TEXTS`], measured by this benchmark with
/// `PATH=$PATH:/path/to/venv/bin cargo host plan-bench` (vpype from PyPI in a
/// venv). Kept so that the goal is tested where vpype is not installed.
pub const VPYPE_BEST_MM: [f64; 3] = [694.4, 760.4, 886.1];

pub struct Row {
    pub name: String,
    /// Pen-up travel read back from the G-code, mm.
    pub travel: f64,
    pub strokes: usize,
    pub millis: f64,
}

pub struct Report {
    pub text: String,
    pub rows: Vec<Row>,
}

impl Report {
    fn travel(&self, prefix: &str) -> Option<f64> {
        self.rows
            .iter()
            .filter(|r| r.name.starts_with(prefix))
            .map(|r| r.travel)
            .min_by(f64::total_cmp)
    }

    /// vpype's best travel, when vpype ran.
    pub fn vpype_best(&self) -> Option<f64> {
        self.travel("vpype")
    }

    /// inkstep's default plan over vpype's best.
    pub fn ratio(&self) -> Option<f64> {
        Some(self.travel("inkstep plan")? / self.vpype_best()?)
    }
}

/// The strokes of a text as `cargo host text` lays them out, in writing order,
/// and the route that command drives by default.
pub fn bench_strokes(text: &str) -> Result<(Vec<Stroke>, Route)> {
    let l = layout(text, SIZE_MM, "futural")?;
    Ok((l.strokes, Route::closed(Pt::new(0.0, 0.0))))
}

/// The pen-up travel of the G-code written for strokes in this order: the
/// writer's output parsed back, every move that does not draw summed.
pub fn gcode_travel(strokes: &[Stroke], route: Route) -> Result<f64> {
    let g = to_gcode(
        strokes,
        &GcodeOptions {
            route,
            ..GcodeOptions::default()
        },
    );
    Ok(toolpath::travel(&toolpath::parse(&g)?))
}

fn row(name: &str, s: &[Stroke], route: Route, millis: f64) -> Result<Row> {
    Ok(Row {
        name: name.to_string(),
        travel: gcode_travel(s, route)?,
        strokes: s.len(),
        millis,
    })
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t0 = Instant::now();
    let r = f();
    (r, t0.elapsed().as_secs_f64() * 1e3)
}

/// Runs every method on one text; `vpype` is the command to call (None skips it).
pub fn run(text: &str, opts: &PlanOptions, vpype: Option<&str>) -> Result<Report> {
    let (strokes, route) = bench_strokes(text)?;
    let mut rows = vec![row("natural (writing order)", &strokes, route, 0.0)?];
    let ends: Vec<_> = strokes.iter().map(|s| (s[0], s[s.len() - 1])).collect();
    let (greedy, ms) =
        timed(|| plan::apply(&strokes, &Problem::new(&ends, route, opts.reverse).greedy()));
    rows.push(row("greedy nearest end", &greedy, route, ms)?);
    let mut quick = *opts;
    quick.effort.kicks = 0;
    let (ours, ms) = timed(|| plan::plan(&strokes, route, &quick));
    rows.push(row("inkstep, local search only", &ours, route, ms)?);
    let (ours, ms) = timed(|| plan::plan(&strokes, route, opts));
    rows.push(row("inkstep plan (default)", &ours, route, ms)?);
    if let Some(cmd) = vpype {
        for (name, args) in [
            ("vpype linesort", &["linesort"][..]),
            ("vpype linesort --two-opt", &["linesort", "--two-opt"][..]),
        ] {
            // vpype starts from the first stroke it is given, so its result
            // depends on the shuffle: its best of a few counts.
            let mut best: Option<Row> = None;
            for seed in SHUFFLES {
                match run_vpype(cmd, args, &shuffled(&strokes, seed)) {
                    Ok((s, ms)) => {
                        if s.len() != strokes.len() {
                            bail!("{name}: {} strokes out of {}", s.len(), strokes.len());
                        }
                        let r = row(name, &s, route, ms)?;
                        if best.as_ref().is_none_or(|b| r.travel < b.travel) {
                            best = Some(r);
                        }
                    }
                    Err(e) => {
                        eprintln!("{name} not measured: {e:#}");
                        break;
                    }
                }
            }
            rows.extend(best);
        }
    }
    Ok(Report {
        text: text.to_string(),
        rows,
    })
}

/// The strokes in a reproducible pseudo-random order (Fisher-Yates).
pub fn shuffled(strokes: &[Stroke], seed: u64) -> Vec<Stroke> {
    let mut s = strokes.to_vec();
    let mut x = seed | 1;
    for i in (1..s.len()).rev() {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        s.swap(i, (x % (i as u64 + 1)) as usize);
    }
    s
}

/// Writes the strokes as SVG (y down, px = mm), runs `cmd read in.svg ARGS
/// write out.svg` and reads the result back into the same frame. Returns the
/// strokes and the wall time of the vpype process in ms (Python start-up
/// included).
pub fn run_vpype(cmd: &str, args: &[&str], strokes: &[Stroke]) -> Result<(Vec<Stroke>, f64)> {
    let dir = std::env::temp_dir().join(format!("inkstep-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let (inp, out) = (dir.join("in.svg"), dir.join("out.svg"));
    let (w, h) = (2000.0, 1000.0);
    std::fs::write(&inp, to_svg(strokes, w, h))?;
    let (st, ms) = timed(|| {
        Command::new(cmd)
            .arg("read")
            .arg(&inp)
            .args(args)
            .arg("write")
            .arg(&out)
            .status()
    });
    let st = st.with_context(|| format!("running {cmd}"))?;
    if !st.success() {
        bail!("{cmd} failed: {st}");
    }
    let text = std::fs::read_to_string(&out)?;
    let mut s = strokes_from_svg(&text, 0.001)?;
    for p in s.iter_mut().flatten() {
        *p = Pt::new(p.x / MM_PER_PX, p.y / MM_PER_PX);
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok((s, ms))
}

/// Strokes as an SVG page of `w` x `h` px with y flipped (SVG y down).
pub fn to_svg(strokes: &[Stroke], w: f64, h: f64) -> String {
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n"
    );
    for st in strokes {
        s.push_str("<polyline fill=\"none\" stroke=\"black\" points=\"");
        for p in st {
            let _ = write!(s, "{},{} ", p.x, h - p.y);
        }
        s.push_str("\"/>\n");
    }
    s.push_str("</svg>\n");
    s
}

/// The table as printed.
pub fn table(r: &Report) -> String {
    let nat = r.rows[0].travel;
    let vp = r.vpype_best();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<26} {:>10} {:>8} {:>11} {:>7} {:>10}",
        "method", "pen-up mm", "/natural", "/vpype best", "strokes", "time ms"
    );
    for row in &r.rows {
        let v = vp.map_or("-".to_string(), |v| format!("{:.3}", row.travel / v));
        let _ = writeln!(
            s,
            "{:<26} {:>10.1} {:>8.3} {:>11} {:>7} {:>10.1}",
            row.name,
            row.travel,
            row.travel / nat,
            v,
            row.strokes,
            row.millis
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn travel_is_read_from_the_gcode_with_the_park() {
        let (s, route) = bench_strokes("风").unwrap();
        // The natural order's gaps from the strokes, plus the way home.
        let mut at = route.start;
        let mut expect = 0.0;
        for st in &s {
            expect += at.dist(st[0]);
            at = *st.last().unwrap();
        }
        expect += at.dist(route.start);
        let got = gcode_travel(&s, route).unwrap();
        // The G-code keeps 3 decimals: each coordinate within 0.0005 mm.
        assert!(
            (got - expect).abs() < 0.001 * (s.len() + 1) as f64,
            "{got} {expect}"
        );
    }

    #[test]
    fn svg_export_round_trips_through_the_reader() {
        let (s, _) = bench_strokes("风").unwrap();
        let mut back = strokes_from_svg(&to_svg(&s, 2048.0, 1024.0), 0.001).unwrap();
        for p in back.iter_mut().flatten() {
            *p = Pt::new(p.x / MM_PER_PX, p.y / MM_PER_PX);
        }
        assert_eq!(back.len(), s.len());
        for (a, b) in s.iter().flatten().zip(back.iter().flatten()) {
            assert!(a.dist(*b) < 0.01, "{a:?} {b:?}");
        }
    }

    #[test]
    fn shuffle_keeps_every_stroke() {
        let (s, _) = bench_strokes("一帆").unwrap();
        let sh = shuffled(&s, 7);
        assert_ne!(sh, s);
        let key = |v: &[Stroke]| {
            let mut k: Vec<String> = v.iter().map(|s| format!("{s:?}")).collect();
            k.sort();
            k
        };
        assert_eq!(key(&sh), key(&s));
    }
}
