//! Issue 16, point 5, and issue 20, point 5, on the firmware: every `?` answered within
//! 2 ms of emulated time (OUT packet to IN packet, and from the sender's write) while a
//! character-counting stream keeps the planner and the receive buffer full. `cargo emu latency` prints the distribution over longer
//! streams (emu/README.md).

mod common;

use inkstep_emu::clock::{T_PER_MS, T_PER_US};
use inkstep_emu::latency::{measure, Load, BOUND};

fn assert_bound(load: Load, lines: usize) {
    let l = measure(common::elf(), load, lines, 10 * T_PER_MS, false).expect("stream");
    let over: Vec<f64> = l
        .answers
        .iter()
        .filter(|&&a| a > BOUND)
        .map(|&a| a as f64 / T_PER_US as f64)
        .collect();
    assert!(
        l.within_bound(),
        "{}: {} questions, median {:.0} µs, max {:.0} µs (from the sender's write {:.0} µs, {} over 2 ms); over 2 ms: {over:?}; unanswered {}; complaints {:?}",
        load.name(),
        l.answers.len(),
        l.quantile_us(0.5),
        l.max_us(),
        l.max_from_write as f64 / T_PER_US as f64,
        l.over_bound_from_write,
        l.unanswered,
        l.complaints
    );
}

#[test]
fn status_answered_within_2_ms_during_a_stream_of_ordinary_moves() {
    assert_bound(Load::Ordinary, 600);
}

/// Every line a curve: an arc's block start (the circle interpolator's set-up and its
/// ramp) is the longest the preparation task runs for one command, and an arc line the
/// longest the protocol task plans. The `?` is answered by the USB task when it
/// arrives (between two lock sections, before the preparation's next run), and an arc
/// line is interpreted and planned in two lock sections (issue 20 point 5: 1,750 µs at
/// worst under the pessimistic model, the default; `cargo emu latency --load arcs`).
#[test]
fn status_answered_within_2_ms_during_a_stream_of_arcs() {
    assert_bound(Load::Arcs, 300);
}

/// The same arc stream under the typical cycle model.
#[test]
fn status_answered_within_2_ms_during_a_stream_of_arcs_under_the_typical_cpu_model() {
    inkstep_emu::cpu_model::CpuModel::set_for_thread(inkstep_emu::cpu_model::CpuModel::Typical);
    assert_bound(Load::Arcs, 300);
}

/// At one step per block every step command is a block start (about 0.1 ms on the
/// board); the preparation task (priority 5, with the USB task, above the protocol)
/// prepares only `pipeline::MIN_AHEAD` (2) commands beyond its 5 ms horizon, so a
/// `?` never waits for a long stretch of them (`cargo emu latency --explain`).
#[test]
fn status_answered_within_2_ms_during_a_stream_of_one_step_moves() {
    assert_bound(Load::OneStep, 3_000);
}
