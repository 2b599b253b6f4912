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
