//! Exact arcs for any centre, end to end: G-code arcs whose centre is off the step grid
//! (I/J offsets that are not whole steps, the R form with positive and negative R, inch
//! units, full circles by I/J) go through the G-code interpreter and the DDA
//! interpolator, and every step is measured against the programmed circle (computed
//! here in f64 from the G-code's numbers) by the simulator's analysis: each must be on the
//! grid point nearest the circle, at most 0.71 step from it (issue 14).

use inkstep_core::gcode::parser::clean_line;
use inkstep_core::gcode::Interpreter;
use inkstep_core::interpolation::{Interpolate, Interpolator, Method};
use inkstep_core::motion::Command;
use inkstep_core::motion::Move;
use inkstep_core::settings::Settings;
use inkstep_sim::analysis::{Analyzer, Ideal};
use proptest::prelude::*;

/// The arc's moves from running `lines` (a G0 to the start, then the arc: one move, or
/// two halves for a full circle), and where they start.
fn arc_move(lines: &[String], s: &Settings) -> (Vec<Move>, [i32; 3]) {
    let mut it = Interpreter::new();
    let mut start = [0; 3];
    let mut arc = Vec::new();
    for line in lines {
        let mut buf: heapless::Vec<u8, 128> = heapless::Vec::new();
        clean_line(line.as_bytes(), &mut buf).expect("clean");
        let o = it.execute(&buf, s, 0).expect("accepted");
        for c in o.cmds.iter() {
            if let Command::Move(m) = c {
                if line.contains("G0") {
                    start = m.target;
                } else {
                    arc.push(*m);
                }
            }
        }
    }
    assert!(!arc.is_empty(), "an arc");
    (arc, start)
}

/// Largest distance (steps) of the trace's steps from the circle around `c` with radius
/// `r` (mm), whether it ended at the last move's target, and the angle its steps swept
/// around `c` (radians, counter-clockwise positive).
fn deviation(mvs: &[Move], start: [i32; 3], c: [f64; 2], r: f64, spm: f64) -> (f64, bool, f64) {
    let mut a = Analyzer::new(Ideal::Circle { c, r }, [spm, spm], start);
    let mut p = start;
    let mut n = 0u64;
    let angle = |p: [i32; 3]| (f64::from(p[1]) - c[1] * spm).atan2(f64::from(p[0]) - c[0] * spm);
    let mut swept = 0.0f64;
    for mv in mvs {
        let mut it = Interpolator::new(p, mv, Method::Dda).expect("an arc");
        while let Some(t) = it.next_event() {
            let before = angle(p);
            t.apply(&mut p);
            let d = angle(p) - before;
            swept +=
                (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
            a.step(n as f64, t.steps(), p);
            n += 1;
            assert!(n < 10_000_000);
        }
    }
    let last = mvs.last().map(|m| m.target);
    (a.finish().max_dev, Some(p) == last, swept)
}

fn settings(spm: f32) -> Settings {
    let mut s = Settings::default();
    s.set(100, spm).unwrap();
    s.set(101, spm).unwrap();
    s
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// I/J arcs (and full circles) around centres anywhere, in mm or inches.
    #[test]
    fn ij_arcs_around_off_grid_centres_stay_within_0_71_step(
        x0 in -60.0f64..60.0, y0 in -60.0f64..60.0, i in -40.0f64..40.0, j in -40.0f64..40.0,
        sweep in 0.0f64..std::f64::consts::TAU, full in any::<bool>(), ccw in any::<bool>(),
        inch in any::<bool>(), spm in prop::sample::select(vec![80.0f32, 100.0, 157.48, 1280.0])) {
        let unit = if inch { 25.4 } else { 1.0 };
        let (x0, y0, i, j) = (x0 / unit, y0 / unit, i / unit, j / unit);
        let r = i.hypot(j);
        prop_assume!(r * unit * f64::from(spm) > 2.0);
        let (cx, cy) = (x0 + i, y0 + j);
        let a0 = (-j).atan2(-i);
        let a1 = if ccw { a0 + sweep } else { a0 - sweep };
        let (x1, y1) = if full { (x0, y0) } else { (cx + r * a1.cos(), cy + r * a1.sin()) };
        let g = if inch { "G20" } else { "G21" };
        // Printed as a CAM program would, to a hundred-thousandth of a mm or a
        // millionth of an inch (f32 holds no more).
        let f = |v: f64| if inch { format!("{v:.6}") } else { format!("{v:.5}") };
        let lines = vec![
            format!("{g} G90 G0 X{} Y{}", f(x0), f(y0)),
            format!("{g} G{} X{} Y{} I{} J{} F1000", if ccw { 3 } else { 2 }, f(x1), f(y1), f(i), f(j)),
        ];
        let s = settings(spm);
        let (mv, start) = arc_move(&lines, &s);
        // The circle the program describes (the printed start and offsets), in mm.
        let p = |v: &str| -> f64 { v.parse().unwrap() };
        let (x0, y0, i, j) = (p(&f(x0)), p(&f(y0)), p(&f(i)), p(&f(j)));
        let c = [(x0 + i) * unit, (y0 + j) * unit];
        let r = i.hypot(j) * unit;
        let (dev, ended, swept) = deviation(&mv, start, c, r, f64::from(spm));
        prop_assert!(ended, "did not end at the target");
        prop_assert!(dev <= 0.71, "deviation {} steps", dev);
        // Drawn once, the right way round, within a step or two at the rounded ends.
        let want = if full { std::f64::consts::TAU } else { sweep };
        let got = if ccw { swept } else { -swept };
        let r_steps = r * f64::from(spm);
        prop_assert!((got - want).abs() * r_steps < 2.0, "swept {got} rad, the arc {want} rad, r {r_steps} steps");
    }

    /// R-form arcs, positive R (at most half a turn) and negative R (more than half).
    #[test]
    fn r_form_arcs_stay_within_0_71_step(
        x0 in -60.0f64..60.0, y0 in -60.0f64..60.0, dx in -50.0f64..50.0, dy in -50.0f64..50.0,
        extra in 0.01f64..30.0, neg in any::<bool>(), ccw in any::<bool>()) {
        let chord = dx.hypot(dy);
        prop_assume!(chord > 0.5);
        let r = chord / 2.0 + extra;
        let (x1, y1) = (x0 + dx, y0 + dy);
        let lines = vec![
            format!("G21 G90 G0 X{x0:.4} Y{y0:.4}"),
            format!("G{} X{x1:.4} Y{y1:.4} R{}{r:.4} F1000", if ccw { 3 } else { 2 }, if neg { "-" } else { "" }),
        ];
        let s = settings(80.0);
        let (mv, start) = arc_move(&lines, &s);
        // The centre in f64: on the chord's bisector, on the side the sign of R and the
        // direction pick.
        let p = |v: &str| -> f64 { v.parse().unwrap() };
        let (x0, y0, x1, y1, r) = (p(&format!("{x0:.4}")), p(&format!("{y0:.4}")), p(&format!("{x1:.4}")), p(&format!("{y1:.4}")), p(&format!("{r:.4}")));
        let (dx, dy) = (x1 - x0, y1 - y0);
        let d = dx.hypot(dy);
        let h = ((r * r - d * d / 4.0).max(0.0)).sqrt() / d;
        let side = if ccw != neg { 1.0 } else { -1.0 };
        let c = [x0 + dx / 2.0 - side * h * dy, y0 + dy / 2.0 + side * h * dx];
        let (dev, ended, _) = deviation(&mv, start, c, r, 80.0);
        prop_assert!(ended, "did not end at the target");
        prop_assert!(dev <= 0.71, "deviation {} steps", dev);
    }
}

/// Full circles by I/J from every start angle, both ways, by either interpolation
/// ($212), on circles from a few steps to 25 mm across, centres off the grid: each is drawn whole, once, and ends where it
/// began. The path of one arc ends at the first pass of its target, and a circle's
/// target is its start: from some angles (the diagonals above all) the trace used to
/// take its start for the pass and draw nothing (one in ten of these).
#[test]
fn full_circles_from_any_start_angle_are_drawn_whole() {
    use inkstep_sim::run::{run_gcode, Flow};
    let (cx, cy) = (40.0037f64, 30.0021f64);
    let mut failures = Vec::new();
    for &r in &[0.06f64, 0.31, 12.504] {
        for k in 0..48 {
            let a = k as f64 * std::f64::consts::TAU / 48.0 + 0.0013;
            let (x, y) = (cx + r * a.cos(), cy + r * a.sin());
            for (g, method) in [
                ("G2", ""),
                ("G3", ""),
                ("G2", "$212=0\n"),
                ("G3", "$212=0\n"),
            ] {
                let program = format!(
                    "{method}G21 G90\nG0 X{x:.4} Y{y:.4}\n{g} X{x:.4} Y{y:.4} I{:.4} J{:.4} F3000\n",
                    cx - x,
                    cy - y
                );
                let run = run_gcode(&program, Flow::SendResponse);
                assert!(run.errors.is_empty() && run.alarms.is_empty(), "{program}");
                // The angle the steps sweep around the centre, in steps (80/mm).
                let c = [cx * 80.0, cy * 80.0];
                // The circle's steps: from where the G0 ended.
                let at = [(x * 80.0).round() as i32, (y * 80.0).round() as i32];
                let start = run
                    .events
                    .iter()
                    .position(|e| [e.pos[0], e.pos[1]] == at)
                    .unwrap_or(run.events.len());
                let arc = &run.events[start..];
                assert_eq!([run.final_pos[0], run.final_pos[1]], at, "{program}");
                let mut swept = 0.0f64;
                for w in arc.windows(2) {
                    let ang = |p: [i32; 3]| (f64::from(p[1]) - c[1]).atan2(f64::from(p[0]) - c[0]);
                    let d = ang(w[1].pos) - ang(w[0].pos);
                    swept += (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI;
                }
                let want = if g == "G3" { 1.0 } else { -1.0 } * std::f64::consts::TAU;
                if (swept - want).abs() * r * 80.0 > 1.0 {
                    failures.push(format!("r {r} a {a:.3} {method}{g}: swept {swept:.3}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} circles not whole: {failures:?}",
        failures.len()
    );
}
