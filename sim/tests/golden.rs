//! Golden tests: every reference program of bench/ run through the simulator
//! (protocol, planner, step engine in virtual time) and measured against its ideal path
//! and Grbl's figures read from the bench README. The goals of the motion issue: job
//! time no longer than Grbl's, max deviation <= 0.71 step, final position exact; and
//! no step wasted (the same step counts as Grbl).

use inkstep_sim::bench::{goal_failures, read_grbl_table, run_program, run_program_after, GrblRow};
use inkstep_sim::paths::{bench_dir, grbl_figures};

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
    assert_eq!(
        [b.ours.steps[0], b.ours.steps[1]],
        g.steps,
        "{program}: steps per axis"
    );
    let fails = goal_failures(&b.ours, &g);
    assert!(fails.is_empty(), "{program}: {}", fails.join("; "));
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
