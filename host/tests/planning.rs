//! Properties of the pen-path planner over random stroke sets: every
//! segment is kept (possibly reversed, never when reversal is off), the
//! result is never worse than the natural order, and Euler joining leaves
//! exactly the minimum number of trails on drawings with junctions.

use inkstep_host::bench::{bench_strokes, gcode_travel, GOAL, TEXTS, VPYPE_BEST_MM};
use inkstep_host::gcode_out::{to_gcode, GcodeOptions, Pen};
use inkstep_host::geom::{pen_up_travel, Pt, Route, Stroke};
use inkstep_host::plan::{euler, plan, Effort, PlanOptions};
use inkstep_host::text::layout;
use inkstep_host::toolpath::{check_grbl, parse, MoveKind};
use proptest::prelude::*;
use std::collections::HashMap;
use std::time::Duration;

type Key = (i64, i64);

fn key(p: Pt) -> Key {
    ((p.x * 1e6).round() as i64, (p.y * 1e6).round() as i64)
}

/// Multiset of segments; undirected ones are stored with sorted ends.
fn segments(strokes: &[Stroke], directed: bool) -> HashMap<(Key, Key), usize> {
    let mut m = HashMap::new();
    for s in strokes {
        if s.len() == 1 {
            *m.entry((key(s[0]), key(s[0]))).or_default() += 1;
        }
        for w in s.windows(2) {
            let (a, b) = (key(w[0]), key(w[1]));
            let k = if directed || a <= b { (a, b) } else { (b, a) };
            *m.entry(k).or_default() += 1;
        }
    }
    m
}

fn quick() -> PlanOptions {
    PlanOptions {
        effort: Effort {
            kicks: 20,
            time_limit: Duration::from_secs(2),
            window: 7,
        },
        ..PlanOptions::default()
    }
}

/// Strokes on a coarse grid, so end points often coincide (junctions).
fn strokes_strategy() -> impl Strategy<Value = Vec<Stroke>> {
    prop::collection::vec(
        prop::collection::vec((0i32..6, 0i32..6), 1..5).prop_map(|v| {
            v.into_iter()
                .map(|(x, y)| Pt::new(x as f64, y as f64))
                .collect()
        }),
        0..30,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn keeps_every_segment_and_never_loses_to_natural(
        strokes in strokes_strategy(), sx in -3.0f64..8.0, sy in -3.0f64..8.0,
        park in prop::option::of((-3.0f64..8.0, -3.0f64..8.0)), reverse: bool, join: bool,
    ) {
        let route = Route { start: Pt::new(sx, sy), park: park.map(|(x, y)| Pt::new(x, y)) };
        let opts = PlanOptions { reverse, join, ..quick() };
        let out = plan(&strokes, route, &opts);
        prop_assert_eq!(segments(&out, !reverse), segments(&strokes, !reverse));
        prop_assert!(pen_up_travel(&out, route) <= pen_up_travel(&strokes, route) + 1e-9);
    }

    #[test]
    fn euler_join_leaves_the_minimum_number_of_trails(
        edges in prop::collection::vec(((0i32..4, 0i32..4), (0i32..4, 0i32..4)), 1..25),
    ) {
        let strokes: Vec<Stroke> = edges
            .iter()
            .filter(|(a, b)| a != b)
            .map(|&((x0, y0), (x1, y1))| vec![Pt::new(x0 as f64, y0 as f64), Pt::new(x1 as f64, y1 as f64)])
            .collect();
        let out = euler::join(&strokes, 1e-6, true);
        prop_assert_eq!(segments(&out, false), segments(&strokes, false));
        // Minimum trails: per connected component, max(1, odd vertices / 2).
        let id = |p: Pt| (p.x as usize) * 4 + p.y as usize;
        let mut parent: Vec<usize> = (0..16).collect();
        fn find(p: &mut Vec<usize>, x: usize) -> usize {
            if p[x] != x { let r = find(p, p[x]); p[x] = r; }
            p[x]
        }
        let mut deg = [0usize; 16];
        for s in &strokes {
            let (a, b) = (id(s[0]), id(s[1]));
            deg[a] += 1;
            deg[b] += 1;
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra] = rb;
        }
        let mut odd: HashMap<usize, usize> = HashMap::new();
        for (v, &d) in deg.iter().enumerate() {
            if d > 0 {
                let r = find(&mut parent, v);
                *odd.entry(r).or_default() += d % 2;
            }
        }
        let expect: usize = odd.values().map(|&o| (o / 2).max(1)).sum();
        prop_assert_eq!(out.len(), expect);
    }
}

#[test]
fn junction_drawing_is_joined_into_few_trails() {
    // 田: a 2x2 grid of unit squares as 12 unit segments. Four odd vertices
    // (the edge midpoints), so two trails instead of twelve strokes.
    let mut strokes = Vec::new();
    for i in 0..3 {
        for j in 0..2 {
            let (i, j) = (i as f64, j as f64);
            strokes.push(vec![Pt::new(j, i), Pt::new(j + 1.0, i)]);
            strokes.push(vec![Pt::new(i, j), Pt::new(i, j + 1.0)]);
        }
    }
    // Open route: the Euler trails end at odd vertices, which a closed tour
    // from a corner may not want (the planner's guard keeps it no worse than the
    // strokes as given, not than every other join).
    let start = Route::open(Pt::new(0.0, 0.0));
    let joined = plan(&strokes, start, &quick());
    assert_eq!(joined.len(), 2);
    let unjoined = plan(
        &strokes,
        start,
        &PlanOptions {
            join: false,
            ..quick()
        },
    );
    // Same or less travel, and 2 pen lifts instead of 12.
    assert!(pen_up_travel(&joined, start) <= pen_up_travel(&unjoined, start) + 1e-9);
    assert_eq!(unjoined.len(), 12);
    assert_eq!(segments(&joined, false), segments(&strokes, false));
}

#[test]
fn text_of_both_scripts_becomes_valid_gcode_that_draws_every_stroke() {
    let l = layout("写字机 Plot 42", 15.0, "futural").unwrap();
    assert_eq!(l.char_starts.len(), 3 + 4 + 2);
    let planned = plan(&l.strokes, Route::closed(Pt::new(0.0, 0.0)), &quick());
    for pen in [
        Pen::M3,
        Pen::Z {
            up: 3.0,
            down: -0.5,
            feed: 300.0,
        },
    ] {
        let g = to_gcode(
            &planned,
            &GcodeOptions {
                pen,
                ..Default::default()
            },
        );
        check_grbl(&g).unwrap();
        // The drawn moves, read back, are exactly the layout's segments
        // (to G-code's 3 decimals).
        let drawn: Vec<Stroke> = parse(&g)
            .unwrap()
            .into_iter()
            .filter(|m| m.kind == MoveKind::Draw)
            .map(|m| vec![m.from, m.to])
            .collect();
        let round = |s: &[Stroke]| -> Vec<Stroke> {
            s.iter()
                .map(|s| {
                    s.iter()
                        .map(|p| Pt::new((p.x * 1e3).round() / 1e3, (p.y * 1e3).round() / 1e3))
                        .collect()
                })
                .collect()
        };
        let expect: Vec<Stroke> = round(&l.strokes)
            .into_iter()
            .filter(|s| s.len() > 1)
            .collect();
        assert_eq!(segments(&round(&drawn), false), segments(&expect, false));
    }
}

#[test]
fn the_driven_route_beats_the_goal_against_vpype_on_every_benchmark_text() {
    // The default plan, measured as plan-bench measures it (the G-code read
    // back, the park included), against vpype's best on the same texts, start
    // and park (stored figures: see bench::VPYPE_BEST_MM; CI also runs vpype).
    for (text, vpype) in TEXTS.iter().zip(VPYPE_BEST_MM) {
        let (strokes, route) = bench_strokes(text).unwrap();
        let out = plan(&strokes, route, &PlanOptions::default());
        assert_eq!(segments(&out, false), segments(&strokes, false));
        let travel = gcode_travel(&out, route).unwrap();
        assert!(
            travel <= GOAL * vpype,
            "{text}: pen-up travel {travel:.1} mm, vpype {vpype:.1} mm: {:.3}x",
            travel / vpype
        );
    }
}
