//! Golden tests: every reference program of bench/ run through the simulator
//! (protocol, planner, step engine in virtual time) and measured against its ideal path
//! and Grbl's figures read from the bench README. The goals of the motion issue: job
//! time no longer than Grbl's, max deviation <= 0.71 step, final position exact; and
//! no step wasted (the same step counts as Grbl, where grbl-sim counted them). The
//! programs of tiny moves compare with the model of Grbl's planner, whose figures in
//! the README are checked against the model here, and the model against grbl-sim.

use inkstep_core::settings::Settings;
use inkstep_sim::bench::{goal_failures, read_grbl_table, run_program, run_program_after, GrblRow};
use inkstep_sim::grbl_model;
use inkstep_sim::paths::{bench_dir, grbl_figures};

/// The programs of tiny moves, whose Grbl figures come from the planner model.
const SHORT_SEGMENTS: [&str; 5] = [
    "zigzag.nc",
    "zigzag-fine.nc",
    "zigzag-shallow.nc",
    "polygon.nc",
    "dashes.nc",
];

fn grbl(program: &str) -> GrblRow {
    let dir = bench_dir();
    let text = std::fs::read_to_string(grbl_figures(&dir)).expect("Grbl's figures");
    read_grbl_table(&text)
        .into_iter()
        .find(|r| r.program == program)
        .expect("program in the table")
}

fn check(program: &str) {
    let g = grbl(program);
    let b = run_program(&bench_dir(), &g).unwrap();
    assert!(
        b.run.ok(),
        "{program}: errors {:?} alarms {:?}",
        b.run.errors,
        b.run.alarms
    );
    if g.max_dev.is_some() {
        // grbl-sim's step counts (the model's are those of the rounded vertices, which a
        // path followed exactly need not make; see polygon.nc).
        assert_eq!(
            [b.ours.steps[0], b.ours.steps[1]],
            g.steps,
            "{program}: steps per axis"
        );
    }
    let fails = goal_failures(&b.ours, &g);
    assert!(fails.is_empty(), "{program}: {}", fails.join("; "));
    // Nothing runs faster than the time-optimal profile of its own limits: a job time
    // below it would mean the limits were broken (or the model is wrong).
    if let Some(optimal) = b.model.optimal {
        assert!(
            b.ours.job_time_s >= optimal * (1.0 - 1e-4),
            "{program}: {} s below the time-optimal {optimal} s",
            b.ours.job_time_s
        );
    }
}

#[test]
fn star() {
    check("star.nc");
}

#[test]
fn circle() {
    check("circle.nc");
}

#[test]
fn sine() {
    check("sine.nc");
}

#[test]
fn spiral() {
    check("spiral.nc");
}

#[test]
fn zigzag() {
    check("zigzag.nc");
}

#[test]
fn zigzag_fine() {
    check("zigzag-fine.nc");
}

#[test]
fn zigzag_shallow() {
    check("zigzag-shallow.nc");
}

#[test]
fn polygon() {
    check("polygon.nc");
}

#[test]
fn dashes() {
    check("dashes.nc");
}

fn model_of(program: &str) -> grbl_model::ModelTimes {
    let text = std::fs::read_to_string(bench_dir().join(program)).expect("program");
    let start_speed = f64::from(Settings::default().start_rate()) / 60.0;
    grbl_model::times(&text, start_speed).expect("the model reads the program")
}

/// The model of Grbl's planner against grbl-sim on the programs it was run on: job time
/// within 0.1 %, the same step counts and final position.
#[test]
fn the_grbl_model_agrees_with_grbl_sim() {
    for program in ["star.nc", "circle.nc", "sine.nc", "spiral.nc"] {
        let g = grbl(program);
        let m = model_of(program);
        let err = (m.grbl / g.job_time_s - 1.0).abs();
        assert!(
            err <= 1e-3,
            "{program}: model {} s, grbl-sim {} s",
            m.grbl,
            g.job_time_s
        );
        assert_eq!(m.steps, g.steps, "{program}");
        assert_eq!([m.end[0] as i32, m.end[1] as i32], g.final_pos, "{program}");
    }
}

/// The README's model figures are what the model computes now.
#[test]
fn the_model_rows_are_the_models_figures() {
    for program in SHORT_SEGMENTS {
        let g = grbl(program);
        let m = model_of(program);
        assert!(
            g.max_dev.is_none(),
            "{program}: a model row has no deviation"
        );
        assert!(
            (m.grbl - g.job_time_s).abs() < 0.5e-4,
            "{program}: {} vs {}",
            m.grbl,
            g.job_time_s
        );
        assert_eq!(m.steps, g.steps, "{program}");
        assert_eq!([m.end[0] as i32, m.end[1] as i32], g.final_pos, "{program}");
    }
}

/// The classic point-by-point method ($212=0, one axis per step) ends exactly where
/// the program does and stays within one step of the path beyond the DDA goal.
#[test]
fn classic_method_stays_within_one_step_on_every_program() {
    for program in ["star.nc", "circle.nc", "sine.nc", "spiral.nc"] {
        let g = grbl(program);
        let b = run_program_after(&bench_dir(), &g, "$212=0\n").unwrap();
        assert!(
            b.run.ok(),
            "{program}: {:?} {:?}",
            b.run.errors,
            b.run.alarms
        );
        assert_eq!(
            [b.ours.final_pos[0], b.ours.final_pos[1]],
            g.final_pos,
            "{program}: final position"
        );
        assert!(b.ours.max_dev < 1.0 + 0.71, "{program}: {}", b.ours.max_dev);
    }
}
