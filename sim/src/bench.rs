//! Bench analysis: measures a step trace against the ideal path of a reference program.
//!
//! Owns the ideal-path JSON format of `bench/*.json`, the figures we compare with
//! Grbl (job time, max/rms deviation, steps per axis, final position; measured with the
//! simulator's `analysis`) and the reading of Grbl's own figures from the bench README, so
//! that no expected number is written into the code. Grbl's figures come from grbl-sim,
//! or, for the programs of tiny moves it was not run on, from the model of Grbl's
//! planner ([`crate::grbl_model`]); those rows have no deviation figures.

use crate::analysis::{self, Analyzer};
use crate::grbl_model::{self, ModelTimes};
use crate::run::Flow;
use crate::run::{run_gcode, RunResult};
use crate::trace::Trace;
use serde::Deserialize;
use std::path::Path;

/// The ideal path a program describes, in millimetres: `{"type": "poly", "pts": [[x, y],
/// ...]}` or `{"type": "circle", "c": [x, y], "r": r}`.
#[derive(Clone, Debug, PartialEq)]
pub enum Ideal {
    Poly { pts: Vec<[f64; 2]> },
    Circle { c: [f64; 2], r: f64 },
}

/// The two shapes' fields, read by the `type` tag. Not serde's internally tagged enum:
/// that buffers the numbers, and with serde_json's `arbitrary_precision` (which
/// defmt-decoder turns on when the workspace is built together) buffered numbers no
/// longer read as f64.
#[derive(Deserialize)]
struct IdealFile {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default)]
    pts: Vec<[f64; 2]>,
    c: Option<[f64; 2]>,
    r: Option<f64>,
}

impl std::str::FromStr for Ideal {
    type Err = String;
    fn from_str(text: &str) -> Result<Ideal, String> {
        let f: IdealFile = serde_json::from_str(text).map_err(|e| e.to_string())?;
        match (f.kind.as_str(), f.c, f.r) {
            ("poly", _, _) => Ok(Ideal::Poly { pts: f.pts }),
            ("circle", Some(c), Some(r)) => Ok(Ideal::Circle { c, r }),
            ("circle", _, _) => Err("a circle needs c and r".into()),
            (other, _, _) => Err(format!("unknown ideal path type {other:?}")),
        }
    }
}

impl Ideal {
    pub fn read_file(path: &Path) -> Result<Ideal, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        text.parse().map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The core's view of the path, for its [`Analyzer`].
    pub fn as_core(&self) -> analysis::Ideal<'_> {
        match self {
            Ideal::Poly { pts } => analysis::Ideal::Poly(pts),
            Ideal::Circle { c, r } => analysis::Ideal::Circle { c: *c, r: *r },
        }
    }
}

/// What we measure of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct Figures {
    /// First motion to last step, seconds.
    pub job_time_s: f64,
    /// Distance of step positions from the ideal path, in steps.
    pub max_dev: f64,
    pub rms_dev: f64,
    pub steps: [u64; 3],
    pub final_pos: [i32; 3],
}

/// Measures `trace` against `ideal`, with `steps_per_mm` on X and Y, through the core's
/// [`Analyzer`] (deviation, steps, end position). The start position (before the first
/// row) is the origin, as in the reference programs; the job time is the last row's
/// time, which counts from the first motion (Grbl: "stepper start to the last step").
pub fn analyse(trace: &Trace, ideal: &Ideal, steps_per_mm: f64) -> Figures {
    let mut a = Analyzer::new(ideal.as_core(), [steps_per_mm; 2], [0; 3]);
    let mut prev = [0i32; 3];
    for row in &trace.rows {
        let mask = (0..3)
            .filter(|&i| row.pos[i] != prev[i])
            .fold(0u8, |m, i| m | 1 << i);
        a.step(row.t_us / 1e6, mask, row.pos);
        prev = row.pos;
    }
    let s = a.finish();
    Figures {
        job_time_s: trace.rows.last().map_or(0.0, |r| r.t_us / 1e6),
        max_dev: s.max_dev,
        rms_dev: s.rms_dev,
        steps: s.steps,
        final_pos: s.end,
    }
}

/// Grbl's figures for one program, as printed in the bench README.
#[derive(Clone, Debug, PartialEq)]
pub struct GrblRow {
    /// File name, e.g. `star.nc`.
    pub program: String,
    /// The description after the file name.
    pub what: String,
    pub job_time_s: f64,
    /// Deviations as grbl-sim measured them; `None` (`-` in the table) for the figures
    /// of the planner model, which makes no steps.
    pub max_dev: Option<f64>,
    pub rms_dev: Option<f64>,
    pub steps: [u64; 2],
    pub final_pos: [i32; 2],
}

/// Reads the markdown table of Grbl's figures from the bench README.
pub fn read_grbl_table(readme: &str) -> Vec<GrblRow> {
    let mut out = Vec::new();
    for line in readme.lines() {
        let cells: Vec<&str> = line
            .trim()
            .trim_matches('|')
            .split('|')
            .map(str::trim)
            .collect();
        if cells.len() != 7 || !cells[0].contains(".nc") {
            continue;
        }
        let (program, what) = cells[0]
            .split_once(char::is_whitespace)
            .unwrap_or((cells[0], ""));
        let num = |s: &str| s.parse::<f64>().ok();
        // A deviation is a number, or `-` where there is none.
        let dev = |s: &str| {
            if s == "-" {
                Some(None)
            } else {
                num(s).map(Some)
            }
        };
        let fin: Vec<i32> = cells[6]
            .split(',')
            .filter_map(|s| s.trim().parse().ok())
            .collect();
        let (Some(t), Some(mx), Some(rms), Some(sx), Some(sy)) = (
            num(cells[1]),
            dev(cells[2]),
            dev(cells[3]),
            num(cells[4]),
            num(cells[5]),
        ) else {
            continue;
        };
        if fin.len() != 2 {
            continue;
        }
        out.push(GrblRow {
            program: program.to_string(),
            what: what.trim().to_string(),
            job_time_s: t,
            max_dev: mx,
            rms_dev: rms,
            steps: [sx as u64, sy as u64],
            final_pos: [fin[0], fin[1]],
        });
    }
    out
}

/// The goals of the motion issue, checked per program.
pub const MAX_DEV_GOAL: f64 = 0.71;

/// Whether `ours` meets every goal against `grbl`: job time no longer, deviation within
/// [`MAX_DEV_GOAL`], final position exact.
pub fn goal_failures(ours: &Figures, grbl: &GrblRow) -> Vec<String> {
    let mut f = Vec::new();
    if ours.job_time_s > grbl.job_time_s {
        f.push(format!(
            "job time {:.4} s > Grbl's {:.4} s",
            ours.job_time_s, grbl.job_time_s
        ));
    }
    if ours.max_dev > MAX_DEV_GOAL {
        f.push(format!(
            "max deviation {:.3} > {MAX_DEV_GOAL}",
            ours.max_dev
        ));
    }
    if [ours.final_pos[0], ours.final_pos[1]] != grbl.final_pos {
        f.push(format!(
            "final position {},{} != {},{}",
            ours.final_pos[0], ours.final_pos[1], grbl.final_pos[0], grbl.final_pos[1]
        ));
    }
    f
}

/// `(Grbl's)` figure of a deviation, `(-)` where it has none.
fn grbl_dev(d: Option<f64>) -> String {
    d.map_or("-".to_string(), |d| format!("{d:.3}"))
}

/// One markdown table with our figures beside Grbl's.
pub fn markdown_table(rows: &[(GrblRow, Figures)]) -> String {
    let mut s = String::from(
        "| program | job time s (Grbl) | max dev steps (Grbl) | rms dev (Grbl) | steps X | steps Y | final | goals |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for (g, o) in rows {
        let fails = goal_failures(o, g);
        s.push_str(&format!(
            "| {} | {:.4} ({:.4}) | {:.3} ({}) | {:.3} ({}) | {} ({}) | {} ({}) | {},{} | {} |\n",
            g.program,
            o.job_time_s,
            g.job_time_s,
            o.max_dev,
            grbl_dev(g.max_dev),
            o.rms_dev,
            grbl_dev(g.rms_dev),
            o.steps[0],
            g.steps[0],
            o.steps[1],
            g.steps[1],
            o.final_pos[0],
            o.final_pos[1],
            if fails.is_empty() {
                "met".to_string()
            } else {
                fails.join("; ")
            }
        ));
    }
    s
}

/// Our job times beside the planner model's: Grbl's (15 blocks of look-ahead) and the
/// time-optimal bound of the same limits at our start speed (whole-program look-ahead;
/// `-` for programs with arcs, which the model cuts into chords as Grbl does and
/// inkstep does not). With grbl-sim's figure where it was measured.
pub fn model_table(runs: &[BenchRun]) -> String {
    let mut s = String::from(
        "| program | blocks | job time s | Grbl: grbl-sim s | Grbl: model s | time-optimal s | job time / optimal |\n\
         |---|---:|---:|---:|---:|---:|---:|\n",
    );
    for b in runs {
        let measured = b
            .grbl
            .max_dev
            .map_or("-".to_string(), |_| format!("{:.4}", b.grbl.job_time_s));
        let (optimal, ratio) = match b.model.optimal {
            Some(o) => (format!("{o:.4}"), format!("{:.4}", b.ours.job_time_s / o)),
            None => ("-".to_string(), "-".to_string()),
        };
        s.push_str(&format!(
            "| {} | {} | {:.4} | {} | {:.4} | {} | {} |\n",
            b.grbl.program,
            b.model.blocks,
            b.ours.job_time_s,
            measured,
            b.model.grbl,
            optimal,
            ratio
        ));
    }
    s
}

/// One reference program run and measured.
pub struct BenchRun {
    pub grbl: GrblRow,
    pub ours: Figures,
    pub run: RunResult,
    /// The planner model's times for the program (Grbl's, and the time-optimal bound at
    /// inkstep's start speed).
    pub model: ModelTimes,
}

/// Runs the program `grbl.program` of `bench_dir` and measures it against its ideal
/// path. The programs set 80 steps/mm on X and Y at their head.
pub fn run_program(bench_dir: &Path, grbl: &GrblRow) -> Result<BenchRun, String> {
    run_program_after(bench_dir, grbl, "")
}

/// [`run_program`] with `setup` lines (e.g. settings) sent before the program.
pub fn run_program_after(
    bench_dir: &Path,
    grbl: &GrblRow,
    setup: &str,
) -> Result<BenchRun, String> {
    let nc = bench_dir.join(&grbl.program);
    let text = std::fs::read_to_string(&nc).map_err(|e| format!("{}: {e}", nc.display()))?;
    let ideal = Ideal::read_file(&nc.with_extension("json"))?;
    let run = run_gcode(&format!("{setup}{text}"), Flow::SendResponse);
    let spmm = f64::from(run.settings.steps_per_mm(0));
    let ours = analyse(&run.trace(), &ideal, spmm);
    let start_speed = f64::from(run.settings.start_rate()) / 60.0;
    let model =
        grbl_model::times(&text, start_speed).map_err(|e| format!("{}: {e}", nc.display()))?;
    Ok(BenchRun {
        grbl: grbl.clone(),
        ours,
        run,
        model,
    })
}

/// Runs every program of the bench README.
pub fn run_all(bench_dir: &Path) -> Result<Vec<BenchRun>, String> {
    let readme = crate::paths::grbl_figures(bench_dir);
    let text =
        std::fs::read_to_string(&readme).map_err(|e| format!("{}: {e}", readme.display()))?;
    let rows = read_grbl_table(&text);
    if rows.is_empty() {
        return Err(format!("{}: no table of Grbl's figures", readme.display()));
    }
    rows.iter().map(|g| run_program(bench_dir, g)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::Row;

    fn trace(points: &[(f64, [i32; 3])]) -> Trace {
        Trace {
            rows: points
                .iter()
                .map(|&(t_us, pos)| Row { t_us, pos })
                .collect(),
        }
    }

    #[test]
    fn parses_both_ideal_kinds() {
        let p: Ideal = r#"{"type": "poly", "pts": [[0.0, 0.0], [1, 2]]}"#.parse().unwrap();
        assert_eq!(
            p,
            Ideal::Poly {
                pts: vec![[0.0, 0.0], [1.0, 2.0]]
            }
        );
        let c: Ideal = r#"{"type": "circle", "c": [20.0, 0.0], "r": 20.0}"#
            .parse()
            .unwrap();
        assert_eq!(
            c,
            Ideal::Circle {
                c: [20.0, 0.0],
                r: 20.0
            }
        );
    }

    #[test]
    fn staircase_on_a_diagonal() {
        // Line (0,0)->(2,2) mm at 1 step/mm, drawn one axis at a time: the off-diagonal
        // corners are 1/sqrt(2) step away.
        let ideal = Ideal::Poly {
            pts: vec![[0.0, 0.0], [2.0, 2.0]],
        };
        let t = trace(&[
            (10.0, [1, 0, 0]),
            (20.0, [1, 1, 0]),
            (30.0, [2, 1, 0]),
            (1_500_000.0, [2, 2, 0]),
        ]);
        let f = analyse(&t, &ideal, 1.0);
        assert!((f.max_dev - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
        assert!((f.rms_dev - (0.25f64).sqrt()).abs() < 1e-12);
        assert_eq!(f.steps, [2, 2, 0]);
        assert_eq!(f.final_pos, [2, 2, 0]);
        assert!((f.job_time_s - 1.5).abs() < 1e-12);
    }

    #[test]
    fn steps_count_back_and_forth() {
        let ideal = Ideal::Poly {
            pts: vec![[0.0, 0.0], [1.0, 0.0]],
        };
        // Out, back with the pen going down, out again: one step per axis per row.
        let t = trace(&[(1.0, [1, 0, 0]), (2.0, [0, 0, -1]), (3.0, [1, 0, 0])]);
        let f = analyse(&t, &ideal, 1.0);
        assert_eq!(f.steps, [3, 0, 2]);
        assert_eq!(f.final_pos, [1, 0, 0]);
    }

    const README: &str = "\
| program | job time s | max deviation (steps) | rms deviation | steps X | steps Y | final position |
|---|---|---|---|---|---|---|
| star.nc   {5/2} star, R 40 mm, F3000 | 8.0403 | 1.029 | 0.351 | 19696 | 18734 | 0,0 |
| sine.nc   y = 10 sin(x/5), 0.5 mm segments, F2000 | 3.2240 | 1.024 | 0.395 | 5024 | 6393 | 5024,-5 |
| zigzag.nc | 12.4645 | - | - | 4000 | 4000 | 4000,0 |
| bad.nc | 1.0 | x | - | 1 | 1 | 0,0 |
";

    #[test]
    fn reads_grbl_table_and_checks_goals() {
        let rows = read_grbl_table(README);
        assert_eq!(rows.len(), 3);
        assert_eq!((rows[2].max_dev, rows[2].rms_dev), (None, None));
        assert_eq!(rows[2].steps, [4000, 4000]);
        assert_eq!(rows[1].max_dev, Some(1.024));
        assert_eq!(rows[1].program, "sine.nc");
        assert_eq!(rows[1].final_pos, [5024, -5]);
        assert_eq!(rows[0].steps, [19696, 18734]);
        assert!((rows[0].job_time_s - 8.0403).abs() < 1e-12);
        let good = Figures {
            job_time_s: 3.0,
            max_dev: 0.7,
            rms_dev: 0.3,
            steps: [5024, 6393, 0],
            final_pos: [5024, -5, 0],
        };
        assert!(goal_failures(&good, &rows[1]).is_empty());
        let slow = Figures {
            job_time_s: 3.3,
            max_dev: 0.8,
            final_pos: [5024, -4, 0],
            ..good.clone()
        };
        assert_eq!(goal_failures(&slow, &rows[1]).len(), 3);
        let table = markdown_table(&[(rows[1].clone(), good)]);
        assert!(table.contains("| sine.nc | 3.0000 (3.2240) |"));
        assert!(table.ends_with("| met |\n"));
    }

    #[test]
    fn reads_grbls_figures_of_the_bench() {
        let path = crate::paths::grbl_figures(&crate::paths::bench_dir());
        let text = std::fs::read_to_string(&path).expect("Grbl's figures of the bench");
        let rows = read_grbl_table(&text);
        let names: Vec<&str> = rows.iter().map(|r| r.program.as_str()).collect();
        assert_eq!(
            names,
            [
                "star.nc",
                "circle.nc",
                "sine.nc",
                "spiral.nc",
                "zigzag.nc",
                "zigzag-fine.nc",
                "zigzag-shallow.nc",
                "polygon.nc",
                "dashes.nc"
            ]
        );
        // grbl-sim's rows carry deviations, the model's do not.
        assert!(rows[..4].iter().all(|r| r.max_dev.is_some()));
        assert!(rows[4..]
            .iter()
            .all(|r| r.max_dev.is_none() && r.rms_dev.is_none()));
    }
}
