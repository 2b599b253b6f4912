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

/// `svg --arcs` on the board: the curves go out as G2/G3 (a circle as two arcs), run
/// through the simulator without an error, and every step the pen makes while down
/// lies within the arc tolerance plus one step of the true curves (flattened here to
/// half a micrometre).
#[test]
fn svg_curves_as_arcs_draw_within_the_tolerance_and_a_step() {
    use inkstep_host::svg_in::{read_svg, SvgOptions};
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="60mm" viewBox="0 0 100 60">
        <circle cx="25" cy="25" r="15" fill="none" stroke="black"/>
        <ellipse cx="70" cy="20" rx="20" ry="8" fill="none" stroke="black"/>
        <path d="M 5 55 C 25 35, 45 65, 65 45 S 90 40, 95 55" fill="none" stroke="black"/>
    </svg>"#;
    let tol = 0.01;
    let d = read_svg(
        svg.as_bytes(),
        &SvgOptions {
            arcs: Some(tol),
            ..SvgOptions::default()
        },
    )
    .expect("svg");
    let strokes = plan(
        &d.strokes(),
        Route::closed(Pt::new(0.0, 0.0)),
        &PlanOptions::default(),
    );
    let g = to_gcode(
        &strokes,
        &GcodeOptions {
            arcs: Some(tol),
            arc_hints: d.arc_hints.clone(),
            ..GcodeOptions::default()
        },
    );
    let arcs = g
        .lines()
        .filter(|l| l.starts_with("G2 ") || l.starts_with("G3 "))
        .count();
    let lines = g.lines().filter(|l| l.starts_with("G1 ")).count();
    assert!(
        (4..=80).contains(&arcs) && lines <= 2,
        "{arcs} arcs, {lines} lines:\n{g}"
    );
    let r = run_gcode(&g, Flow::CharCount(128));
    assert!(r.errors.is_empty(), "errors {:?}", r.errors);
    assert!(r.alarms.is_empty() && !r.timed_out);
    let truth: Vec<Vec<Pt>> = strokes_from_svg(svg, 0.0005).expect("svg");
    let spmm = 80.0;
    let mut down = 0;
    let mut worst = 0.0f64;
    for e in r.events.iter().filter(|e| e.servo_down || e.pos[2] < 0) {
        let p = Pt::new(f64::from(e.pos[0]) / spmm, f64::from(e.pos[1]) / spmm);
        let d = truth
            .iter()
            .flat_map(|s| s.windows(2))
            .map(|w| inkstep_host::svg_in::dist_to_segment(p, w[0], w[1]))
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(d);
        down += 1;
    }
    eprintln!("{arcs} arcs; {down} pen-down steps, the farthest {worst:.4} mm from the curves");
    assert!(down > 10_000, "{down} steps with the pen down");
    assert!(
        worst <= tol + 1.0 / spmm,
        "a step {worst} mm from the curves"
    );
}
