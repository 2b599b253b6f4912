//! The motion benchmark: runs the four reference programs of `bench/` through the
//! planner, segment preparation and step interrupt in virtual time, measures job time,
//! deviation from the ideal path and the end position, and compares with Grbl 1.1h's
//! figures (bench/GRBL.md) on the same programs and settings.
//!
//! Run: cargo test -p inkstep-core --target host-tuple --profile host --test bench -- --nocapture
//!
//! The programs are read by `inkstep_core::refprog` (only what they use); lines carry
//! their exact end points (1/256 step, `Path::LineFine`), so steps follow the
//! programmed path rather than the path between rounded ends.

use inkstep_core::analysis::{Analyzer, Ideal, TraceStats};
use inkstep_core::interpolation::Method;
use inkstep_core::motion::{Move, StepPos};
use inkstep_core::planner::PlannerConfig;
use inkstep_core::refprog::RefProgram;
use inkstep_core::stepper::drive::VirtualMachine;
use inkstep_core::stepper::prep::PrepConfig;
use std::fs;

fn bench_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../bench")
}

/// Settings and moves of a program.
fn read_program(text: &str) -> (PlannerConfig, Vec<Move>) {
    let p = RefProgram::new(text, PlannerConfig::default());
    (p.config(), p.collect())
}

/// Grbl's row for a program from bench/GRBL.md: (job time, max deviation).
fn grbl_figures(name: &str) -> (f64, f64) {
    let md = fs::read_to_string(bench_dir().join("GRBL.md")).expect("GRBL.md");
    let row = md
        .lines()
        .find(|l| l.starts_with(&format!("| {name}")))
        .expect("row");
    let cols: Vec<&str> = row.split('|').map(str::trim).collect();
    (
        cols[2].parse().expect("time"),
        cols[3].parse().expect("dev"),
    )
}

fn run(name: &str, method: Method) -> (TraceStats, StepPos) {
    let dir = bench_dir();
    let text = fs::read_to_string(dir.join(format!("{name}.nc"))).expect("program");
    let (mut cfg, moves) = read_program(&text);
    cfg.method = method;
    let json: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join(format!("{name}.json"))).expect("ideal"))
            .expect("json");
    let pts: Vec<[f64; 2]> = json["pts"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
                .collect()
        })
        .unwrap_or_default();
    let ideal = if json["type"] == "circle" {
        Ideal::Circle {
            c: [
                json["c"][0].as_f64().unwrap(),
                json["c"][1].as_f64().unwrap(),
            ],
            r: json["r"].as_f64().unwrap(),
        }
    } else {
        Ideal::Poly(&pts)
    };
    let spmm = [
        f64::from(cfg.axes[0].steps_per_mm),
        f64::from(cfg.axes[1].steps_per_mm),
    ];
    let mut an = Analyzer::new(ideal, spmm, [0; 3]);
    let prep = PrepConfig::default();
    let hz = f64::from(prep.timer_hz);
    let mut vm = VirtualMachine::new(cfg, prep, [0; 3]);
    let mut it = moves.iter().peekable();
    // Stream like a sender: keep the planner topped up while the machine runs.
    while it.peek().is_some() || !vm.is_idle() {
        while let Some(m) = it.peek() {
            if vm.planner.is_full() {
                break;
            }
            vm.push(m).expect("move accepted");
            it.next();
        }
        let until = vm.now() + 72_000; // 1 ms of virtual time
        vm.run_until(until, &mut |e| an.step(e.t as f64 / hz, e.step, e.pos));
    }
    let expected_end = moves.last().map(|m| m.target).unwrap_or([0; 3]);
    (an.finish(), expected_end)
}

#[test]
fn reference_programs_beat_grbl() {
    println!("| program | inkstep s (first to last step) | inkstep s (timer start to last step) | Grbl s | inkstep max dev (steps) | Grbl | rms | steps X | steps Y | final position |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for name in ["star", "circle", "sine", "spiral"] {
        let (s, end) = run(name, Method::Dda);
        let (g_time, g_dev) = grbl_figures(&format!("{name}.nc"));
        println!(
            "| {name}.nc | {:.4} | {:.4} | {g_time:.4} | {:.3} | {g_dev:.3} | {:.3} | {} | {} | {},{} |",
            s.job_time, s.last_step, s.max_dev, s.rms_dev, s.steps[0], s.steps[1], s.end[0], s.end[1]
        );
        if s.job_time > g_time {
            failures.push(format!(
                "{name}: job time {:.4} > Grbl {g_time}",
                s.job_time
            ));
        }
        if s.max_dev > 0.71 {
            failures.push(format!("{name}: deviation {:.3} > 0.71", s.max_dev));
        }
        if s.end != end {
            failures.push(format!("{name}: ended at {:?}, expected {end:?}", s.end));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn classic_method_stays_within_one_step_on_every_program() {
    for name in ["star", "circle", "sine", "spiral"] {
        let (s, end) = run(name, Method::Classic);
        assert_eq!(s.end, end, "{name}");
        assert!(s.max_dev < 1.0 + 0.71, "{name}: {}", s.max_dev);
    }
}
