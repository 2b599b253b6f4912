use super::*;
use crate::gcode::parser::clean_line;
use crate::gcode::units::nm_to_mm;

fn run(it: &mut Interpreter, s: &Settings, line: &str) -> Result<Outcome, Reject> {
    let mut buf: heapless::Vec<u8, 128> = heapless::Vec::new();
    clean_line(line.as_bytes(), &mut buf).map_err(Reject::Error)?;
    it.execute(&buf, s, 7)
}

fn moves(o: &Outcome) -> std::vec::Vec<Move> {
    o.cmds
        .iter()
        .filter_map(|c| match c {
            Command::Move(m) => Some(*m),
            _ => None,
        })
        .collect()
}

fn err(n: ErrorCode) -> Result<Outcome, Reject> {
    Err(Reject::Error(n))
}

#[test]
fn lines_round_to_steps_and_carry_feed_and_line_numbers() {
    let s = Settings::default(); // 80 step/mm on X and Y
    let mut it = Interpreter::new();
    let o = run(&mut it, &s, "G1 X10.0031 Y-0.00624 F600").unwrap();
    // The rounded target, and the exact ends in 1/256 step for the interpolator:
    // 10.0031 mm = 800.248 steps = 204,863.488 / 256, -0.00624 mm = -0.4992 steps
    // = -127.7952 / 256 (f32 mm had made the first 204,864).
    assert_eq!(
        moves(&o),
        [Move {
            target: [800, 0, 0],
            path: Path::LineFine {
                from: [0, 0],
                to: [204863, -128]
            },
            feed: Feed::MmPerMin(600.0),
            line: 7
        }]
    );
    let o = run(&mut it, &s, "N42 G91 X1 Y1").unwrap();
    let m = moves(&o)[0];
    assert_eq!((m.target, m.line), ([880, 80, 0], 42));
    let o = run(&mut it, &s, "G0 X-1").unwrap();
    assert_eq!(moves(&o)[0].feed, Feed::Rapid);
    assert_eq!(moves(&o)[0].target, [800, 80, 0]);
    // Inches apply to axes and feed.
    let o = run(&mut it, &s, "G20 G90 G1 X1 F10").unwrap();
    assert_eq!(moves(&o)[0].target, [2032, 80, 0]);
    assert_eq!(moves(&o)[0].feed, Feed::MmPerMin(254.0));
}

#[test]
fn grbl_error_numbers_for_bad_blocks() {
    let s = Settings::default();
    let mut it = Interpreter::new();
    assert_eq!(run(&mut it, &s, "G1 X1"), err(ErrorCode::UndefinedFeedRate));
    assert_eq!(
        run(&mut it, &s, "G0 G1 X1"),
        err(ErrorCode::ModalGroupViolation)
    );
    assert_eq!(
        run(&mut it, &s, "G5 X1"),
        err(ErrorCode::UnsupportedCommand)
    );
    assert_eq!(run(&mut it, &s, "G0 X1 I2"), err(ErrorCode::UnusedWords));
    assert_eq!(
        run(&mut it, &s, "G0 G92 X1"),
        err(ErrorCode::AxisCommandConflict)
    );
    assert_eq!(run(&mut it, &s, "G80 X1"), err(ErrorCode::AxisWordsExist));
    assert_eq!(run(&mut it, &s, "G4"), err(ErrorCode::ValueWordMissing));
    assert_eq!(run(&mut it, &s, "G4 P-1"), err(ErrorCode::NegativeValue));
    assert_eq!(
        run(&mut it, &s, "N10000001 G0 X1"),
        err(ErrorCode::InvalidLineNumber)
    );
    assert_eq!(
        run(&mut it, &s, "G59.1"),
        err(ErrorCode::CommandValueNotInteger)
    );
    assert_eq!(
        run(&mut it, &s, "G53 G2 X1 I1 F10"),
        err(ErrorCode::G53InvalidMotionMode)
    );
    assert_eq!(run(&mut it, &s, "G2 I1 F10"), err(ErrorCode::NoAxisWords));
    assert_eq!(
        run(&mut it, &s, "G2 Z1 I1 F10"),
        err(ErrorCode::NoAxisWordsInPlane)
    );
    assert_eq!(
        run(&mut it, &s, "G2 X1 F10"),
        err(ErrorCode::NoOffsetsInPlane)
    );
    assert_eq!(
        run(&mut it, &s, "G2 X10 R2 F10"),
        err(ErrorCode::ArcRadiusError)
    );
    assert_eq!(
        run(&mut it, &s, "G2 X0 R2 F10"),
        err(ErrorCode::InvalidTarget)
    );
    assert_eq!(
        run(&mut it, &s, "G10 L3 P1 X1"),
        err(ErrorCode::UnsupportedCommand)
    );
    assert_eq!(
        run(&mut it, &s, "G10 L2 P7 X1"),
        err(ErrorCode::UnsupportedCoordSys)
    );
    assert_eq!(run(&mut it, &s, "M62"), err(ErrorCode::UnsupportedCommand));
    assert_eq!(
        run(&mut it, &s, "M0 M6"),
        err(ErrorCode::ModalGroupViolation)
    );
    assert_eq!(
        run(&mut it, &s, "G1.5 X1"),
        err(ErrorCode::CommandValueNotInteger)
    );
    assert_eq!(run(&mut it, &s, "T300"), err(ErrorCode::MaxValueExceeded));
    // A rejected block changes nothing.
    assert_eq!(it, Interpreter::new());
}

#[test]
fn every_g_code_lands_in_its_modal_group() {
    let s = Settings::default();
    // Each supported code with its modal group (Grbl's groups).
    let codes: [(&str, u8); 31] = [
        ("G0", 1),
        ("G1", 1),
        ("G2", 1),
        ("G3", 1),
        ("G80", 1),
        ("G4", 0),
        ("G10", 0),
        ("G28", 0),
        ("G28.1", 0),
        ("G30", 0),
        ("G30.1", 0),
        ("G53", 0),
        ("G92", 0),
        ("G92.1", 0),
        ("G17", 2),
        ("G20", 6),
        ("G21", 6),
        ("G90", 3),
        ("G91", 3),
        ("G91.1", 4),
        ("G93", 5),
        ("G94", 5),
        ("G40", 7),
        ("G43.1", 8),
        ("G49", 8),
        ("G54", 12),
        ("G55", 12),
        ("G56", 12),
        ("G57", 12),
        ("G58", 12),
        ("G59", 12),
    ];
    for (a, ga) in codes {
        for (b, gb) in codes {
            let r = run(&mut Interpreter::new(), &s, &std::format!("{a} {b}"));
            let violation = r == err(ErrorCode::ModalGroupViolation);
            assert_eq!(violation, ga == gb, "{a} {b}: {r:?}");
        }
    }
    let modal = |line: &str| {
        let mut it = Interpreter::new();
        run(&mut it, &s, line).unwrap();
        *it.modal()
    };
    assert_eq!(modal("G1 F100").motion, MotionMode::Linear);
    assert_eq!(modal("G0").motion, MotionMode::Rapid);
    assert_eq!(modal("G2 X1 I0.5 F100").motion, MotionMode::ArcCw);
    assert_eq!(modal("G3 X1 I0.5 F100").motion, MotionMode::ArcCcw);
    assert_eq!(modal("G80").motion, MotionMode::Cancel);
    assert!(modal("G20").inches && !modal("G21").inches);
    assert!(modal("G91").incremental && !modal("G90").incremental);
    assert!(modal("G93").inverse_time && !modal("G94").inverse_time);
    for (k, w) in ["G54", "G55", "G56", "G57", "G58", "G59"]
        .iter()
        .enumerate()
    {
        assert_eq!(usize::from(modal(w).wcs), k);
    }
    assert_eq!(modal("G61 G17 G91.1 G40 G49 G94").motion, MotionMode::Rapid);
}

/// The exact start and centre of an arc, in 1/256 step, and its direction.
fn fine_arc(m: &Move) -> ([i32; 2], [i32; 2], bool) {
    let Path::ArcFine {
        from, center, ccw, ..
    } = m.path
    else {
        panic!("not a fine arc: {:?}", m.path)
    };
    (from, center, ccw)
}

#[test]
fn arcs_in_ij_and_r_form_with_cam_tolerance() {
    let s = Settings::default();
    let mut it = Interpreter::new();
    let o = run(&mut it, &s, "G2 X10 Y0 I5 J0 F300").unwrap();
    let m = moves(&o)[0];
    assert_eq!(m.target, [800, 0, 0]);
    // Exact start and centre in 1/256 step (5 mm = 400 steps).
    assert_eq!(fine_arc(&m), ([0, 0], [102_400, 0], false));
    // Negative R: the long way round (centre on the other side).
    let mut it = Interpreter::new();
    let short = moves(&run(&mut it, &s, "G2 X10 Y0 R7.0710678 F300").unwrap())[0];
    let mut it = Interpreter::new();
    let long = moves(&run(&mut it, &s, "G2 X10 Y0 R-7.0710678 F300").unwrap())[0];
    let near =
        |c: [i32; 2], want: [i32; 2]| (c[0] - want[0]).abs() <= 2 && (c[1] - want[1]).abs() <= 2;
    assert!(near(fine_arc(&short).1, [102_400, -102_400]), "{short:?}");
    assert!(near(fine_arc(&long).1, [102_400, 102_400]), "{long:?}");
    // End point 0.004 mm off the circle (CAM rounding) is accepted, 0.1 mm is not.
    let mut it = Interpreter::new();
    assert!(run(&mut it, &s, "G3 X10.004 Y0 I5 F300").is_ok());
    let mut it = Interpreter::new();
    assert_eq!(
        run(&mut it, &s, "G3 X10.1 Y0 I5 F300"),
        err(ErrorCode::InvalidTarget)
    );
    // Full circle with I/J (target equals start): two halves, to the point opposite
    // the start and back, so that the path's end is never ambiguous.
    let mut it = Interpreter::new();
    let full = moves(&run(&mut it, &s, "G3 X0 Y0 I5 F300").unwrap());
    assert_eq!(full.len(), 2);
    assert_eq!(full[0].target, [800, 0, 0]);
    assert_eq!(fine_arc(&full[0]), ([0, 0], [102_400, 0], true));
    assert_eq!(full[1].target, [0, 0, 0]);
    assert_eq!(fine_arc(&full[1]), ([204_800, 0], [102_400, 0], true));
    assert_eq!(full[0].feed, full[1].feed);
    // Inch units and offsets between steps: the centre keeps its fraction of a step.
    let mut it = Interpreter::new();
    let inch = moves(&run(&mut it, &s, "G20 G3 X0 Y0 I0.123 J0.0457 F10").unwrap())[0];
    let q = |mm: f32| (mm * 80.0 * 256.0).round() as i32;
    assert!(
        near(fine_arc(&inch).1, [q(0.123 * 25.4), q(0.0457 * 25.4)]),
        "{inch:?}"
    );
}

#[test]
fn arcs_with_unequal_resolution_become_ellipses_in_step_space() {
    let mut s = Settings::default();
    s.set(101, 40.0).unwrap();
    let mut it = Interpreter::new();
    let m = moves(&run(&mut it, &s, "G3 X10 Y0 I5 F300").unwrap())[0];
    assert_eq!(m.target, [800, 0, 0]);
    assert_eq!(
        m.path,
        Path::Ellipse {
            center: [400, 0],
            a: 400,
            b: 200,
            ccw: true
        }
    );
}

proptest::proptest! {
    /// R-form arcs: the centre is equidistant from both ends, on the side that
    /// gives at most half a turn for positive R and at least half for negative R.
    #[test]
    fn r_form_centres_are_consistent(
        x0 in -100.0f32..100.0, y0 in -100.0f32..100.0,
        dx in -50.0f32..50.0, dy in -50.0f32..50.0,
        extra in 0.0f32..50.0, neg in proptest::bool::ANY, ccw in proptest::bool::ANY,
    ) {
        let chord = libm::hypotf(dx, dy);
        proptest::prop_assume!(chord > 0.5);
        let r = chord / 2.0 + extra + 0.01;
        let s = Settings::default();
        let mut it = Interpreter::new();
        run(&mut it, &s, &std::format!("G0 X{x0:.4} Y{y0:.4}")).unwrap();
        let start = it.position().map(nm_to_mm);
        let line = std::format!("G{} X{:.4} Y{:.4} R{}{:.4} F100", if ccw { 3 } else { 2 }, x0 + dx, y0 + dy, if neg { "-" } else { "" }, r);
        let o = run(&mut it, &s, &line).unwrap();
        let m = moves(&o)[0];
        let (_, center, dir) = fine_arc(&m);
        proptest::prop_assert_eq!(dir, ccw);
        let spm = s.steps_per_mm(0);
        // The exact centre, in 1/256 step.
        let c = [center[0] as f32 / (256.0 * spm), center[1] as f32 / (256.0 * spm)];
        let end = it.position().map(nm_to_mm);
        let r0 = libm::hypotf(start[0] - c[0], start[1] - c[1]);
        let r1 = libm::hypotf(end[0] - c[0], end[1] - c[1]);
        proptest::prop_assert!((r0 - r1).abs() < 0.1 / spm, "r0 {} r1 {}", r0, r1);
        // Which side: cross product of chord and centre offset.
        let cross = dx * (c[1] - start[1]) - dy * (c[0] - start[0]);
        let short = (cross > 0.0) == ccw; // centre left of travel for a short CCW arc
        if extra > 0.5 {
            proptest::prop_assert_eq!(short, !neg, "cross {}", cross);
        }
    }
}

/// A near-semicircle whose centre lies close to the chord (where the R form is most
/// sensitive): the centre is the exact one, to the 1/256 step.
#[test]
fn r_form_near_semicircle_centre_is_exact() {
    let s = Settings::default();
    let mut it = Interpreter::new();
    run(&mut it, &s, "G0 X40.4444 Y-47.9680").unwrap();
    let o = run(&mut it, &s, "G2 X84.4295 Y-30.6952 R24.8752 F100").unwrap();
    let (from, center, _) = fine_arc(&moves(&o)[0]);
    // Exact centre (65.28043, -46.57250) mm = (5222.43, -3725.80) steps.
    assert!(
        (center[0] - 1_336_943).abs() <= 64 && (center[1] + 953_805).abs() <= 64,
        "{center:?}"
    );
    assert_eq!(
        from,
        [
            (40.4444f32 * 80.0 * 256.0).round() as i32,
            (-47.968f32 * 80.0 * 256.0).round() as i32
        ]
    );
}

#[test]
fn targets_beyond_the_step_range_are_refused() {
    let s = Settings::default();
    let mut it = Interpreter::new();
    assert_eq!(
        run(&mut it, &s, "G0 X99999999"),
        err(ErrorCode::InvalidTarget)
    );
    assert_eq!(it.jog(b"X99999999F10", &s), Err(ErrorCode::InvalidTarget));
    assert_eq!(it, Interpreter::new());
}

#[test]
fn work_offsets_g92_g10_g28_g53() {
    let s = Settings::default();
    let mut it = Interpreter::new();
    run(&mut it, &s, "G10 L2 P2 X10 Y20").unwrap();
    run(&mut it, &s, "G55 G0 X1 Y1").unwrap();
    assert_eq!(it.position(), &[11_000_000, 21_000_000, 0]);
    run(&mut it, &s, "G92 X0 Y0").unwrap();
    let o = run(&mut it, &s, "G0 X1").unwrap();
    assert_eq!(moves(&o)[0].target, [12 * 80, 21 * 80, 0]);
    run(&mut it, &s, "G92.1").unwrap();
    let o = run(&mut it, &s, "G53 G0 X0 Y0").unwrap();
    assert_eq!(moves(&o)[0].target, [0, 0, 0]);
    run(&mut it, &s, "G0 X5 Y5").unwrap(); // G55: machine 15, 25
    run(&mut it, &s, "G28.1").unwrap();
    assert_eq!(it.coords().g28, [15_000_000, 25_000_000, 0]);
    run(&mut it, &s, "G53 G0 X0 Y0").unwrap();
    let o = run(&mut it, &s, "G28 G91 X1").unwrap();
    let ms = moves(&o);
    assert_eq!(ms.len(), 2, "intermediate point, then the stored position");
    assert_eq!(ms[0].target, [80, 0, 0]);
    assert_eq!(ms[1].target, [15 * 80, 25 * 80, 0]);
    run(&mut it, &s, "G90 G10 L20 P0 X0").unwrap();
    assert_eq!(it.work_offset()[0], 15_000_000);
    // G92 and G10 L20 on Z look past the other offsets and the tool length offset.
    let mut it = Interpreter::new();
    run(&mut it, &s, "G10 L2 P1 Z5").unwrap();
    run(&mut it, &s, "G43.1 Z2").unwrap();
    run(&mut it, &s, "G0 Z0").unwrap();
    assert_eq!(it.position()[2], 7_000_000);
    run(&mut it, &s, "G92 Z1").unwrap();
    assert_eq!(it.g92()[2], -1_000_000, "7 - (5 + 2) - 1");
    run(&mut it, &s, "G10 L20 P1 Z0").unwrap();
    assert_eq!(it.coords().wcs[0][2], 6_000_000, "7 - (-1 + 2) - 0");
    assert_eq!(it.work_offset()[2], 7_000_000, "Z reads 0");
}

#[test]
fn pen_dwell_and_program_end() {
    let mut s = Settings::default();
    let mut it = Interpreter::new();
    let o = run(&mut it, &s, "M3 G1 X1 F100").unwrap();
    assert_eq!(moves(&o)[0].target, [0, 0, -800], "Z pen drops first");
    assert_eq!(moves(&o)[1].target, [80, 0, -800]);
    let o = run(&mut it, &s, "G4 P0.25").unwrap();
    assert_eq!(&o.cmds[..], &[Command::Dwell { ms: 250 }]);
    let o = run(&mut it, &s, "M30").unwrap();
    assert_eq!(o.stop, Some(Stop::End));
    assert_eq!(moves(&o)[0].target, [80, 0, 0], "program end lifts the pen");
    assert_eq!(it.modal().motion, MotionMode::Linear);
    s.set(201, 1.0).unwrap();
    let o = run(&mut it, &s, "M3").unwrap();
    assert_eq!(&o.cmds[..], &[Command::Pen { level: PEN_FULL }]);
    let o = run(&mut it, &s, "M3").unwrap();
    assert!(o.cmds.is_empty(), "no change, nothing queued");
    assert_eq!(run(&mut it, &s, "M0").unwrap().stop, Some(Stop::Pause));
}

/// `M3 S` puts the pen in proportion within $31..$30 (S max = down): the servo's
/// level, the Z pen's height; a new S while down is a new height in order with
/// the strokes; `M3` without any S drops it fully; `M5` lifts.
#[test]
fn m3_s_sets_the_pen_height_within_the_spindle_range() {
    let mut s = Settings::default();
    s.set(201, 1.0).unwrap();
    let mut it = Interpreter::new();
    let pen = |o: &Outcome| -> std::vec::Vec<Command> {
        o.cmds
            .iter()
            .copied()
            .filter(|c| matches!(c, Command::Pen { .. }))
            .collect()
    };
    assert_eq!(
        pen(&run(&mut it, &s, "M3").unwrap()),
        [Command::Pen { level: PEN_FULL }]
    );
    assert_eq!(
        pen(&run(&mut it, &s, "M5").unwrap()),
        [Command::Pen { level: 0 }]
    );
    assert_eq!(
        pen(&run(&mut it, &s, "M3 S500").unwrap()),
        [Command::Pen { level: 500 }]
    );
    let o = run(&mut it, &s, "G1 X1 F100 S250").unwrap();
    assert_eq!(o.cmds[0], Command::Pen { level: 250 }, "before the stroke");
    assert!(matches!(o.cmds[1], Command::Move(_)));
    assert!(
        pen(&run(&mut it, &s, "G1 X2 S250").unwrap()).is_empty(),
        "same S"
    );
    assert_eq!(
        pen(&run(&mut it, &s, "S2000").unwrap()),
        [Command::Pen { level: PEN_FULL }]
    );
    assert_eq!(
        pen(&run(&mut it, &s, "M5").unwrap()),
        [Command::Pen { level: 0 }]
    );
    assert!(
        pen(&run(&mut it, &s, "S800").unwrap()).is_empty(),
        "S while up"
    );
    assert_eq!(
        pen(&run(&mut it, &s, "M3").unwrap()),
        [Command::Pen { level: 800 }],
        "modal S"
    );
    s.set(31, 200.0).unwrap();
    assert_eq!(
        pen(&run(&mut it, &s, "S200").unwrap()),
        [Command::Pen { level: 0 }],
        "S min: up"
    );

    // The Z pen: between $205 (0) and $206 (-2 mm), 400 steps/mm.
    let s = Settings::default();
    let mut it = Interpreter::new();
    let o = run(&mut it, &s, "M3 S250").unwrap();
    assert_eq!(moves(&o)[0].target, [0, 0, -200]);
    let o = run(&mut it, &s, "S1000").unwrap();
    assert_eq!(moves(&o)[0].target, [0, 0, -800]);
    let o = run(&mut it, &s, "M5").unwrap();
    assert_eq!(moves(&o)[0].target, [0, 0, 0]);
}

/// `M6 T2`: lift, to the pen-change place ($216-$218), pause (the split), back,
/// down again at the same height; without a place only the lift and drop.
#[test]
fn m6_lifts_goes_to_the_pen_change_place_and_comes_back() {
    let mut s = Settings::default();
    for (n, v) in [(201, 1.0), (216, 1.0), (217, 10.0), (218, 20.0)] {
        s.set(n, v).unwrap();
    }
    let mut it = Interpreter::new();
    run(&mut it, &s, "G0 X5 Y5").unwrap();
    run(&mut it, &s, "M3 S600").unwrap();
    let o = run(&mut it, &s, "M6 T2").unwrap();
    assert_eq!(o.stop, Some(Stop::PenChange { tool: 2, split: 2 }));
    assert!(o.sync, "at rest only");
    assert_eq!(o.cmds[0], Command::Pen { level: 0 });
    assert_eq!(moves(&o)[0].target, [800, 1600, 0], "to the place");
    assert_eq!(moves(&o)[1].target, [400, 400, 0], "and back");
    assert_eq!(o.cmds[3], Command::Pen { level: 600 });
    assert_eq!(it.position(), &[5_000_000, 5_000_000, 0]);
    s.set(216, 0.0).unwrap();
    run(&mut it, &s, "M5").unwrap();
    let o = run(&mut it, &s, "T7").unwrap();
    assert!(o.cmds.is_empty());
    let o = run(&mut it, &s, "M6").unwrap();
    assert_eq!(
        o.stop,
        Some(Stop::PenChange { tool: 7, split: 0 }),
        "the last T"
    );
    assert!(o.cmds.is_empty(), "pen up, no place: nothing moves");
}

#[test]
fn modal_report_names_every_changed_mode() {
    let s = Settings::default();
    let report = |it: &Interpreter| {
        let mut v: heapless::Vec<u8, 64> = heapless::Vec::new();
        it.write_modal(&mut v);
        std::string::String::from_utf8(v.to_vec()).unwrap()
    };
    let mut it = Interpreter::new();
    assert_eq!(report(&it), "GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0");
    run(&mut it, &s, "G20 G91 G93 G59 M3 G1 X1 F1 S12").unwrap();
    assert_eq!(report(&it), "GC:G1 G59 G17 G20 G91 G93 M3 M9 T0 F0 S12");
    run(&mut it, &s, "G21 G90 G94 G56 M5 G80 F300").unwrap();
    assert_eq!(report(&it), "GC:G80 G56 G17 G21 G90 G94 M5 M9 T0 F300 S12");
}

#[test]
fn inverse_time_feed_needs_f_every_block() {
    let s = Settings::default();
    let mut it = Interpreter::new();
    let o = run(&mut it, &s, "G93 G1 X10 F2").unwrap();
    assert_eq!(moves(&o)[0].feed, Feed::MmPerMin(20.0));
    assert_eq!(
        run(&mut it, &s, "G1 X20"),
        err(ErrorCode::UndefinedFeedRate)
    );
    run(&mut it, &s, "G94").unwrap();
    assert_eq!(
        run(&mut it, &s, "G1 X20"),
        err(ErrorCode::UndefinedFeedRate)
    );
}

#[test]
fn soft_limits_reject_targets_and_arc_extents() {
    let mut s = Settings::default();
    s.set(22, 1.0).unwrap();
    s.set(20, 1.0).unwrap(); // X, Y in [0, 300] x [0, 200]
    let mut it = Interpreter::new();
    assert!(run(&mut it, &s, "G0 X100 Y100").is_ok());
    assert_eq!(run(&mut it, &s, "G0 X301"), Err(Reject::SoftLimit));
    assert_eq!(run(&mut it, &s, "G0 Y-0.1"), Err(Reject::SoftLimit));
    // Ends inside, but the arc bulges below Y = 0.
    assert_eq!(
        run(&mut it, &s, "G2 X100 Y100 J-60 F100"),
        Err(Reject::SoftLimit)
    );
    assert!(run(&mut it, &s, "G2 X100 Y100 J-50 F100").is_ok());
    assert_eq!(it.jog(b"G91X-200F100", &s), Err(ErrorCode::TravelExceeded));
    assert!(it.jog(b"G91X-100F100", &s).is_ok());
    assert_eq!(it.jog(b"G1X1F100", &s), Err(ErrorCode::InvalidJogCommand));
    assert_eq!(it.jog(b"X1", &s), Err(ErrorCode::UndefinedFeedRate));
}

/// The keypad's jog is a value, not text: the move it makes is the one the `$J=` line
/// that says the same makes, whatever the modal units and offsets (the keypad always
/// jogs in mm from where the machine is), and the interpreter continues from the same
/// end either way.
#[test]
fn a_keypad_jog_value_moves_as_its_j_line_does() {
    let s = Settings::default();
    for setup in ["G21 G90", "G20 G90", "G21 G91", "G21 G90 G92 X5 Y-3"] {
        let mut by_line = Interpreter::new();
        let mut by_value = Interpreter::new();
        for it in [&mut by_line, &mut by_value] {
            run(it, &s, "G0 X10 Y20").unwrap();
            run(it, &s, setup).unwrap();
        }
        let line = by_line.jog(b"G91G21X-7.5Y2F450", &s).unwrap();
        let value = by_value
            .jog_move(
                &Jog {
                    axes: [Some(-7_500_000), Some(2_000_000), None],
                    frame: JogFrame::Incremental,
                    feed_mm_min: 450.0,
                },
                &s,
            )
            .unwrap();
        assert_eq!(line, value, "{setup}");
        // 80 steps/mm: X 10 - 7.5 = 2.5 mm, Y 20 + 2 = 22 mm.
        assert_eq!(line.target[..2], [200, 1760], "{setup}");
        // Both interpreters continue from the jog's end.
        let next = |it: &mut Interpreter| moves(&run(it, &s, "G91 G21 G1 X1 F100").unwrap());
        assert_eq!(next(&mut by_line), next(&mut by_value), "{setup}");
    }
}

#[test]
fn interpret_changes_nothing_until_commit() {
    // The machine reads a sync point while moving, waits for rest and reads it again:
    // the first reading must leave no trace, whatever the block changes.
    let s = Settings::default();
    let mut it = Interpreter::new();
    run(&mut it, &s, "G1 X5 Y5 F600").unwrap();
    let before = it.clone();
    for line in [
        "G10L2P2X10Y20",
        "G10L20P1X0",
        "G28.1",
        "G30.1",
        "G92X1",
        "G55G91G20G0X1",
        "M3S500",
        "G43.1Z2",
        "M6T3",
        "G20M2",
    ] {
        let mut out = Outcome::default();
        it.interpret(line.as_bytes(), &s, 1, &mut out).unwrap();
        assert_eq!(it, before, "{line}");
        // Committed, the block has its effect: the same as `execute`.
        let mut committed = it.clone();
        committed.commit(&out);
        let mut executed = it.clone();
        executed.execute(line.as_bytes(), &s, 1).unwrap();
        assert_eq!(committed, executed, "{line}");
        assert_ne!(committed, before, "{line}");
    }
    // The stored coordinates change only through `out.coords`.
    let mut out = Outcome::default();
    it.interpret(b"G10L2P2X10Y20", &s, 1, &mut out).unwrap();
    assert_eq!(
        out.coords,
        Some(CoordChange::Wcs {
            index: 1,
            offset: [10_000_000, 20_000_000, 0]
        })
    );
    it.commit(&out);
    assert_eq!(it.coords().wcs[1], [10_000_000, 20_000_000, 0]);
}

#[test]
fn an_arc_sliver_whose_ends_share_a_step_is_not_a_full_circle() {
    // CAM output has arcs of a few micrometres; ends that round to the same step made
    // the path's whole turn: a 10 mm circle drawn for a 0.005 mm arc.
    let s = Settings::default();
    let mut it = Interpreter::new();
    run(&mut it, &s, "G0 X10 Y0").unwrap();
    let o = run(&mut it, &s, "G3 X9.999999 Y0.005 I-10 J0 F600").unwrap();
    assert!(moves(&o).is_empty(), "no step to make: {o:?}");
    // Rising meanwhile: straight up, no circle.
    let o = run(&mut it, &s, "G2 X10 Y0 Z1 I-9.999999 J-0.005").unwrap();
    assert_eq!(moves(&o).len(), 1);
    assert!(matches!(moves(&o)[0].path, Path::Line), "{o:?}");
    // The same ends the other way round are nearly a whole turn: a circle.
    let o = run(&mut it, &s, "G3 X9.999999 Y-0.005 I-10 J0").unwrap();
    assert!(matches!(moves(&o)[0].path, Path::ArcFine { .. }), "{o:?}");
    // And a full circle stays one (in two halves).
    let o = run(&mut it, &s, "G2 X9.999999 Y-0.005 I-9.999999 J0.005").unwrap();
    assert!(matches!(moves(&o)[0].path, Path::ArcFine { .. }), "{o:?}");
}
