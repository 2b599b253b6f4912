//! The planning benchmark (`cargo host plan-bench`): the same strokes from
//! the same start through natural order, greedy nearest-neighbour, our
//! planner and, when it is installed, vpype's `linesort --two-opt`, whose
//! output SVG is read back and measured with our own travel code. Units are
//! 1/1024 of the character box (the character box is laid out at 1024), the
//! pen starts at the top-left corner of the first box, as the CEO measured.

use crate::geom::{pen_down_length, pen_up_travel, Pt, Stroke};
use crate::plan::{self, order::Problem, PlanOptions};
use crate::svg_in::{strokes_from_svg, MM_PER_PX};
use crate::text::layout;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::process::Command;
use std::time::Instant;

pub const DEFAULT_TEXT: &str = "一帆风顺中国地质大学写字机器人";

pub struct Row {
    pub name: String,
    pub travel: f64,
    pub millis: f64,
    pub strokes: usize,
    pub down: f64,
}

/// The strokes and start point of the benchmark text.
pub fn bench_strokes(text: &str) -> Result<(Vec<Stroke>, Pt)> {
    let l = layout(text, 1024.0, "futural")?;
    Ok((l.strokes, Pt::new(0.0, 1024.0)))
}

fn row(name: &str, s: &[Stroke], start: Pt, t0: Instant) -> Row {
    Row {
        name: name.to_string(),
        millis: t0.elapsed().as_secs_f64() * 1e3,
        travel: pen_up_travel(s, start),
        strokes: s.len(),
        down: pen_down_length(s),
    }
}

/// Runs every method; `vpype` is the command to call (None skips it).
pub fn run(text: &str, opts: &PlanOptions, vpype: Option<&str>) -> Result<Vec<Row>> {
    let (strokes, start) = bench_strokes(text)?;
    let mut rows = vec![row(
        "natural (writing order)",
        &strokes,
        start,
        Instant::now(),
    )];
    let t0 = Instant::now();
    let ends: Vec<_> = strokes.iter().map(|s| (s[0], *s.last().unwrap())).collect();
    let greedy = plan::apply(&strokes, &Problem::new(&ends, start, opts.reverse).greedy());
    rows.push(row("greedy nearest end", &greedy, start, t0));
    let t0 = Instant::now();
    let mut quick = *opts;
    quick.effort.kicks = 0;
    let ours = plan::plan(&strokes, start, &quick);
    rows.push(row("inkstep, local search only", &ours, start, t0));
    let t0 = Instant::now();
    let ours = plan::plan(&strokes, start, opts);
    rows.push(row("inkstep plan (default)", &ours, start, t0));
    let t0 = Instant::now();
    let keep = PlanOptions {
        reverse: false,
        ..*opts
    };
    let ours = plan::plan(&strokes, start, &keep);
    rows.push(row("inkstep --keep-direction", &ours, start, t0));
    if let Some(cmd) = vpype {
        match run_vpype(cmd, &strokes) {
            Ok((s, ms)) => {
                let mut r = row("vpype linesort --two-opt", &s, start, Instant::now());
                r.millis = ms;
                rows.push(r);
            }
            Err(e) => eprintln!("vpype not measured: {e:#}"),
        }
    }
    Ok(rows)
}

/// Writes the strokes as SVG (y down, px = units), runs vpype on it and
/// reads the result back into the same frame. Returns the strokes and the
/// wall time of the vpype process in ms (Python start-up included).
pub fn run_vpype(cmd: &str, strokes: &[Stroke]) -> Result<(Vec<Stroke>, f64)> {
    let dir = std::env::temp_dir().join(format!("inkstep-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let (inp, out) = (dir.join("in.svg"), dir.join("out.svg"));
    let (w, h) = (16.0 * 1024.0 * 16.0, 1024.0);
    std::fs::write(&inp, to_svg(strokes, w, h))?;
    let t0 = Instant::now();
    let st = Command::new(cmd)
        .arg("read")
        .arg(&inp)
        .args(["linesort", "--two-opt", "write"])
        .arg(&out)
        .status()
        .with_context(|| format!("running {cmd}"))?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
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
pub fn table(rows: &[Row]) -> String {
    let nat = rows[0].travel;
    let vp = rows
        .iter()
        .find(|r| r.name.starts_with("vpype"))
        .map(|r| r.travel);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<26} {:>10} {:>8} {:>8} {:>7} {:>9} {:>10}",
        "method", "pen-up", "/natural", "/vpype", "strokes", "pen-down", "time ms"
    );
    for r in rows {
        let v = vp.map_or("-".to_string(), |v| format!("{:.3}", r.travel / v));
        let _ = writeln!(
            s,
            "{:<26} {:>10.0} {:>8.3} {:>8} {:>7} {:>9.0} {:>10.1}",
            r.name,
            r.travel,
            r.travel / nat,
            v,
            r.strokes,
            r.down,
            r.millis
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_matches_the_reference_measurement() {
        // The CEO's figure for the natural stroke order is 36116.
        let (s, start) = bench_strokes(DEFAULT_TEXT).unwrap();
        assert_eq!(s.len(), 92);
        assert!((pen_up_travel(&s, start) - 36116.0).abs() < 1.0);
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
}
