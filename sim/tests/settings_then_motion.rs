//! Settings lines and the moves after them arrive in one burst with character counting
//! (a sender fills the 128-byte buffer): the protocol runs them in order, and the moves
//! must be planned with the new limits and never dropped. The planner used to be
//! rebuilt only after the burst, losing the moves queued in it.

use inkstep_sim::run::run_gcode;
use inkstep_sim::run::Flow;

#[test]
fn a_move_right_after_settings_in_the_same_burst_is_drawn() {
    let program = "$110=5000\n$111=5000\n$120=500\n$121=500\nG21 G90\nG2 X0 Y0 I20 J0 F3000\n";
    for flow in [Flow::CharCount(128), Flow::SendResponse] {
        let r = run_gcode(program, flow);
        assert!(
            r.errors.is_empty() && r.alarms.is_empty(),
            "{:?} {:?}",
            r.errors,
            r.alarms
        );
        let x = r.events.iter().filter(|e| e.step & 1 != 0).count();
        let y = r.events.iter().filter(|e| e.step & 2 != 0).count();
        assert_eq!((x, y), (6400, 6400), "full circle of R20 at 80 steps/mm");
        assert_eq!(r.final_pos, [0, 0, 0]);
    }
}

#[test]
fn the_reference_circle_streams_with_character_counting() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../bench/circle.nc"))
        .expect("bench/circle.nc");
    let r = run_gcode(&text, Flow::CharCount(128));
    assert!(r.errors.is_empty() && r.alarms.is_empty());
    assert_eq!(r.events.iter().filter(|e| e.step & 1 != 0).count(), 6400);
}

/// `$213` lets a move start at once up to the start rate; a move slower than that
/// runs at its own feed, not at the start rate (it ran at `$213`: 1 mm at F30 took
/// 1 s). 80 steps/mm: 80 steps 25 ms apart, the first at once.
#[test]
fn a_feed_below_the_start_rate_runs_at_its_own_feed() {
    for head in ["", "$213=0\n", "$213=600\n"] {
        let r = run_gcode(
            &format!("{head}G21 G90\nG1 X1 F30\nG1 X2 F3000\nG1 X1.5 F15\nG4 P0\n"),
            Flow::CharCount(128),
        );
        assert!(r.errors.is_empty() && r.alarms.is_empty(), "{head}");
        let hz = f64::from(inkstep_core::stepper::TIMER_HZ);
        let at = |x: i32| {
            let e = r.events.iter().find(|e| e.pos[0] == x).expect("reached");
            e.t as f64 / hz
        };
        // From the first step to the 80th: 79 intervals of 1/80 mm at 0.5 mm/s.
        let slow = at(80) - at(1);
        assert!(
            (slow - 79.0 / 40.0).abs() < 0.01,
            "{head}: F30 took {slow} s"
        );
        // The way back, 40 steps at 0.25 mm/s (from step 159 to 120).
        let last = r.events.last().unwrap().t as f64 / hz;
        let back = last - r.events.iter().rev().find(|e| e.pos[0] == 159).unwrap().t as f64 / hz;
        assert!(
            (back - 39.0 / 20.0).abs() < 0.01,
            "{head}: F15 took {back} s"
        );
        assert_eq!(r.final_pos[0], 120);
    }
}
