//! The host tool's G-code runs on the machine: text and SVG drawings, planned, in both
//! pen conventions, streamed with character counting through the simulator (the same
//! core protocol, interpreter and planner as the board) without an error or alarm, and
//! the pen ends where the program says.

use inkstep_host::gcode_out::{to_gcode, GcodeOptions, Pen};
use inkstep_host::geom::{Pt, Route};
use inkstep_host::plan::{plan, PlanOptions};
use inkstep_host::svg_in::strokes_from_svg;
use inkstep_host::text::layout;
use inkstep_sim::run::run_gcode;
use inkstep_sim::run::Flow;

fn run_clean(gcode: &str, what: &str) {
    let r = run_gcode(gcode, Flow::CharCount(128));
    assert!(r.errors.is_empty(), "{what}: errors {:?}", r.errors);
    assert!(r.alarms.is_empty(), "{what}: alarms {:?}", r.alarms);
    assert!(!r.timed_out, "{what}: never finished");
    assert!(!r.events.is_empty(), "{what}: nothing was drawn");
    // Every program returns to its home (the origin) with the pen up.
    assert_eq!(
        [r.final_pos[0], r.final_pos[1]],
        [0, 0],
        "{what}: final position"
    );
}

#[test]
fn text_in_both_scripts_runs_through_the_simulator_in_both_pen_modes() {
    let lay = layout("一帆风顺 Hello", 12.0, "futural").expect("layout");
    let strokes = plan(
        &lay.strokes,
        Route::closed(Pt::new(0.0, 0.0)),
        &PlanOptions::default(),
    );
    run_clean(
        &to_gcode(&strokes, &GcodeOptions::default()),
        "text, M3 pen",
    );
    let z = GcodeOptions {
        pen: Pen::Z {
            up: 2.0,
            down: 0.0,
            feed: 600.0,
        },
        ..GcodeOptions::default()
    };
    run_clean(&to_gcode(&strokes, &z), "text, Z pen");
}

#[test]
fn svg_shapes_run_through_the_simulator() {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="60mm" height="40mm" viewBox="0 0 60 40">
        <rect x="2" y="2" width="20" height="12"/>
        <circle cx="40" cy="12" r="8"/>
        <path d="M 5 30 C 15 20, 25 40, 35 30 S 55 20, 58 35"/>
        <polyline points="10,38 20,33 30,38"/>
    </svg>"#;
    let strokes = strokes_from_svg(svg, 0.05).expect("svg");
    assert!(strokes.len() >= 4);
    let strokes = plan(
        &strokes,
        Route::closed(Pt::new(0.0, 0.0)),
        &PlanOptions::default(),
    );
    run_clean(&to_gcode(&strokes, &GcodeOptions::default()), "svg");
}

#[test]
fn svg_arcs_run_through_the_simulator() {
    // The same curves as G2/G3: the machine takes them without an error and
    // ends home; the program is a fraction of the flattened one.
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="60mm" height="40mm" viewBox="0 0 60 40">
        <circle cx="40" cy="12" r="8" fill="none" stroke="black"/>
        <circle cx="10" cy="10" r="0.4" fill="none" stroke="black"/>
        <ellipse cx="20" cy="25" rx="15" ry="6" fill="none" stroke="black"/>
        <path d="M 5 30 C 15 20, 25 40, 35 30 S 55 20, 58 35" fill="none" stroke="black"/>
    </svg>"#;
    let strokes = plan(
        &strokes_from_svg(svg, 0.05).expect("svg"),
        Route::closed(Pt::new(0.0, 0.0)),
        &PlanOptions::default(),
    );
    let flat = to_gcode(&strokes, &GcodeOptions::default());
    let arcs = to_gcode(
        &strokes,
        &GcodeOptions {
            arcs: Some(0.01),
            ..GcodeOptions::default()
        },
    );
    assert!(arcs.contains("G2 ") || arcs.contains("G3 "));
    assert!(arcs.lines().count() * 3 < flat.lines().count());
    run_clean(&arcs, "svg with arcs");
}
