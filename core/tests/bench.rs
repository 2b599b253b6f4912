//! The motion benchmark: runs the four reference programs of `bench/` through the
//! planner, segment preparation and step interrupt in virtual time, measures job time,
//! deviation from the ideal path and the end position, and compares with Grbl 1.1h's
//! figures (bench/GRBL.md) on the same programs and settings.
//!
//! Run: cargo test -p inkstep-core --target host-tuple --profile host --test bench -- --nocapture
//!
//! The G-code reader here understands only what the four programs use ($ settings,
//! G0-G3 with X Y I J F, G4, modal words); the product's interpreter is the protocol
//! issue's. Lines carry their exact end points (1/256 step, `Path::LineFine`), so
//! steps follow the programmed path rather than the path between rounded ends.

use inkstep_core::analysis::{Analyzer, Ideal, TraceStats};
use inkstep_core::interp::Method;
use inkstep_core::motion::{Feed, Move, Path, StepPos};
use inkstep_core::planner::PlannerConfig;
use inkstep_core::stepper::drive::VirtualMachine;
use inkstep_core::stepper::prep::PrepConfig;
use std::fs;

fn bench_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../bench")
}

/// Settings and moves of a program.
fn read_program(text: &str) -> (PlannerConfig, Vec<Move>) {
    let mut cfg = PlannerConfig::default();
    let mut moves = Vec::new();
    let mut pos = [0.0f64; 3];
    let mut feed = 0.0f32;
    let mut motion = 0u32;
    // Settings come first, so steps/mm are known before any move.
    for line in text.lines() {
        let line = line.trim();
        if let Some(rest) = line.strip_prefix('$') {
            let (k, v) = rest.split_once('=').expect("setting");
            let v: f32 = v.parse().expect("value");
            match k {
                "100" | "101" | "102" => {
                    cfg.axes[k.as_bytes()[2] as usize - b'0' as usize].steps_per_mm = v
                }
                "110" | "111" | "112" => {
                    cfg.axes[k.as_bytes()[2] as usize - b'0' as usize].max_rate = v
                }
                "120" | "121" | "122" => {
                    cfg.axes[k.as_bytes()[2] as usize - b'0' as usize].accel = v
                }
                "11" => cfg.junction_deviation = v,
                _ => {}
            }
            continue;
        }
        let mut words = Vec::new();
        let bytes: Vec<char> = line.chars().filter(|c| !c.is_whitespace()).collect();
        let mut i = 0;
        while i < bytes.len() {
            let letter = bytes[i].to_ascii_uppercase();
            let mut j = i + 1;
            while j < bytes.len()
                && (bytes[j].is_ascii_digit() || bytes[j] == '.' || bytes[j] == '-')
            {
                j += 1;
            }
            let num: f64 = bytes[i + 1..j]
                .iter()
                .collect::<String>()
                .parse()
                .expect("number");
            words.push((letter, num));
            i = j;
        }
        let mut target = pos;
        let mut ij = [0.0f64; 2];
        let mut has_axis = false;
        for &(l, n) in &words {
            match l {
                'G' if n <= 3.0 => motion = n as u32,
                'G' if n == 4.0 => motion = 4,
                'X' => (target[0], has_axis) = (n, true),
                'Y' => (target[1], has_axis) = (n, true),
                'Z' => (target[2], has_axis) = (n, true),
                'I' => ij[0] = n,
                'J' => ij[1] = n,
                'F' => feed = n as f32,
                _ => {}
            }
        }
        if !has_axis || motion == 4 {
            continue;
        }
        let q8 = |mm: f64, axis: usize| {
            (mm * f64::from(cfg.axes[axis].steps_per_mm) * 256.0).round() as i32
        };
        let steps = |mm: f64, axis: usize| (f64::from(q8(mm, axis)) / 256.0).round() as i32;
        let t: StepPos = [
            steps(target[0], 0),
            steps(target[1], 1),
            steps(target[2], 2),
        ];
        let path = match motion {
            2 | 3 => Path::Arc {
                center: [steps(ij[0], 0), steps(ij[1], 1)],
                ccw: motion == 3,
                turns: 0,
            },
            _ if target[2] == pos[2] => Path::LineFine {
                from: [q8(pos[0], 0), q8(pos[1], 1)],
                to: [q8(target[0], 0), q8(target[1], 1)],
            },
            _ => Path::Line,
        };
        let feed = if motion == 0 {
            Feed::Rapid
        } else {
            Feed::MmPerMin(feed)
        };
        moves.push(Move {
            target: t,
            path,
            feed,
            line: moves.len() as u32 + 1,
        });
        pos = target;
    }
    (cfg, moves)
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
    println!("| program | inkstep job time s | Grbl s | inkstep max dev (steps) | Grbl | rms | steps X | steps Y | final position |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for name in ["star", "circle", "sine", "spiral"] {
        let (s, end) = run(name, Method::Dda);
        let (g_time, g_dev) = grbl_figures(&format!("{name}.nc"));
        println!(
            "| {name}.nc | {:.4} | {g_time:.4} | {:.3} | {g_dev:.3} | {:.3} | {} | {} | {},{} |",
            s.job_time, s.max_dev, s.rms_dev, s.steps[0], s.steps[1], s.end[0], s.end[1]
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
