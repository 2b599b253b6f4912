//! Every output pin of the wiring table and every setting that acts on a pin or a time,
//! observed on the real image (issue 23, must-show 3): the step pulses' width `$0` and
//! the inversions `$2`/`$3`/`$4` read back to the reported position, the 4-phase coil
//! sequences both ways on both axes, the servo's pulse widths `$202`/`$203` and the
//! lift time `$204`, limit/home switches at positions (homing both axes, a hard limit),
//! the same at inverted levels (`$5`), only on the axes with a switch (`$214`), the
//! e-stop with the alarm's buzzer pattern, the error and done beeps from the keypad,
//! feed hold/SYNC and cycle start from the pins, `$215`, the homing rates and debounce
//! `$24`-`$26`, the servo speed `$208`, steps per mm and rates per axis `$100`-`$112`,
//! soft limits `$20`/`$130`/`$131`. The outside is driven as `cargo emu run --switch/--input` drives it
//! (src/pins.rs).

mod common;

use common::{booted, STEPS_PER_MM};
use inkstep_core::pipeline::{RESUME_MS, START_LEAD_MS};
use inkstep_emu::clock::{T_PER_MS, T_PER_S};
use inkstep_emu::pins::{InputEvent, PosSwitch, Schedule, OUTPUT_WATCH};
use inkstep_emu::session::Session;

const PA: usize = 0;
const T_PER_US: u64 = T_PER_MS / 1000;

fn ok(s: &mut Session, line: &str) {
    let got = s.command(line, 3 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "{line}: {got:?}");
}

/// A board with every output of the wiring table logged.
fn board() -> Session<'static> {
    let mut s = booted(None);
    for (w, add) in s.m.board().watch.iter_mut().zip(OUTPUT_WATCH) {
        *w |= add;
    }
    s
}

/// Run until the machine reports Idle; the machine position in steps.
fn rest_mpos(s: &mut Session) -> [i32; 3] {
    s.wait_idle(60 * T_PER_S).unwrap();
    let st = s.status().unwrap();
    assert!(!st.work, "MPos reports");
    let p = st.pos.unwrap();
    [
        (p[0] * STEPS_PER_MM).round() as i32,
        (p[1] * STEPS_PER_MM).round() as i32,
        (p[2] * 400.0).round() as i32,
    ]
}

/// Changes of PA`n` after `t0`: (time, level).
fn changes(s: &Session, p: usize, n: usize, t0: u64) -> Vec<(u64, bool)> {
    s.m.state()
        .board
        .pin_changes
        .iter()
        .filter(|c| c.0 >= t0 && c.1 == p && c.2 == n)
        .map(|c| (c.0, c.3))
        .collect()
}

fn ms(t: u64) -> f64 {
    t as f64 / T_PER_MS as f64
}

/// `$2`, `$3`, `$4` and `$0` in several combinations: the step pins idle at the `$2`
/// level and every pulse leaves it for `$0` µs, the trace (leading edges, directions
/// read with `$3`) ends where `MPos` says, and /EN (PA9) is at the `$4` level while
/// the drivers are on.
#[test]
fn step_pulses_follow_0_2_3_and_4_and_decode_to_the_reported_position() {
    for (inv, dir, en, width) in [
        (0u8, 0u8, 0u8, 10u32),
        (7, 0, 1, 20),
        (0, 7, 0, 10),
        (5, 2, 1, 40),
    ] {
        let mut s = board();
        for l in [
            format!("$2={inv}"),
            format!("$3={dir}"),
            format!("$4={en}"),
            format!("$0={width}"),
            "$1=255".into(),
        ] {
            ok(&mut s, &l);
        }
        let t0 = s.now();
        ok(&mut s, "G21 G91 G1 F1200 X2 Y-1");
        ok(&mut s, "G1 X-3 Y2");
        let mpos = rest_mpos(&mut s);
        let b = &s.m.state().board;
        let case = format!("$2={inv} $3={dir} $4={en} $0={width}");
        assert_eq!(b.pos[..2], mpos[..2], "{case}: the trace ends at MPos");
        assert_eq!(mpos[..2], [-80, 80], "{case}");
        for a in 0..2 {
            let idle = inv & (1 << a) != 0;
            assert_eq!(
                s.m.state().board.pin(PA, a),
                idle,
                "{case}: PA{a} idles at the $2 level"
            );
            let ch = changes(&s, PA, a, t0);
            let leading: Vec<&(u64, bool)> = ch.iter().filter(|c| c.1 != idle).collect();
            assert_eq!(leading.len() as u64, 80 * [5, 3][a], "{case}: PA{a} pulses");
            let mut stretched = 0;
            for w in ch.windows(2).filter(|w| w[0].1 != idle) {
                let us = (w[1].0 - w[0].0) as f64 / T_PER_US as f64;
                // Never shorter than $0 (what a driver needs). A step interrupt that
                // restarts the one-pulse timer late stretches the pulse by its lateness:
                // at most the longest section that holds it back (under 50 µs), and
                // only now and then.
                assert!(
                    us > f64::from(width) - 0.1 && us < f64::from(width) + 50.0,
                    "{case}: PA{a} pulse {us} µs"
                );
                if us > f64::from(width) + 0.5 {
                    stretched += 1;
                }
            }
            assert!(
                stretched * 50 <= leading.len(),
                "{case}: PA{a}: {stretched} of {} pulses stretched by a late restart",
                leading.len()
            );
        }
        assert_eq!(
            s.m.state().board.pin(PA, 9),
            en == 1,
            "{case}: /EN at the enabled level ($1=255 keeps it)"
        );
    }
}

/// The coil pattern (bit 0 = coil A) of X (PA0-PA3) or Y (PA4-PA7) now.
fn coils(s: &Session, axis: usize) -> u8 {
    (0..4).fold(0, |v, i| {
        v | u8::from(s.m.state().board.pin(PA, 4 * axis + i)) << i
    })
}

/// `$200=1`: each axis's coils walk the half-step sequence A, AB, B, BC, C, CD, D, DA
/// forward for a positive move and backward for a negative one, one position per step,
/// on both axes, and the trace read from the coils ends where `MPos` says.
#[test]
fn four_phase_coils_walk_the_half_step_sequence_both_ways_on_both_axes() {
    use inkstep_core::stepper::phase4::HALF_STEP;
    let mut s = board();
    ok(&mut s, "$200=1");
    ok(&mut s, "$1=255");
    ok(&mut s, "G21 G91 G1 F300");
    let mut want = [0i32; 2];
    for (axis, mm) in [(0usize, 0.5f64), (0, -0.25), (1, 0.5), (1, -0.75)] {
        // From power-up the coils are off and the sequence starts at A.
        let before = match coils(&s, axis) {
            0 => HALF_STEP[0],
            c => c,
        };
        let t0 = s.now();
        let name = ["X", "Y"][axis];
        ok(&mut s, &format!("G1 {name}{mm}"));
        let mpos = rest_mpos(&mut s);
        want[axis] += (mm * STEPS_PER_MM).round() as i32;
        assert_eq!(mpos[..2], want, "{name}{mm}: MPos");
        assert_eq!(
            s.m.state().board.pos[..2],
            want,
            "{name}{mm}: the coils' trace"
        );
        // Every pattern the axis's coils showed, in order.
        let mut seen = vec![before];
        let mut last = t0;
        let mut times: Vec<u64> =
            s.m.state()
                .board
                .pin_changes
                .iter()
                .filter(|c| c.0 > t0 && c.1 == PA && c.2 / 4 == axis && c.2 < 8)
                .map(|c| c.0)
                .collect();
        times.dedup();
        for t in times {
            // The pattern after all changes at this time.
            let mut p = *seen.last().unwrap();
            for c in
                s.m.state()
                    .board
                    .pin_changes
                    .iter()
                    .filter(|c| c.0 == t && c.1 == PA && c.2 / 4 == axis && c.2 < 8)
            {
                let bit = 1 << (c.2 % 4);
                p = if c.3 { p | bit } else { p & !bit };
            }
            assert!(t >= last);
            last = t;
            seen.push(p);
        }
        let step: i32 = if mm > 0.0 { 1 } else { -1 };
        for w in seen.windows(2) {
            let i = HALF_STEP.iter().position(|&c| c == w[0]).unwrap() as i32;
            let j = HALF_STEP.iter().position(|&c| c == w[1]).unwrap() as i32;
            assert_eq!(
                (j - i).rem_euclid(8),
                step.rem_euclid(8),
                "{name}{mm}: {:#x} -> {:#x}",
                w[0],
                w[1]
            );
        }
        assert_eq!(
            seen.len() as i32 - 1,
            (mm * STEPS_PER_MM).abs().round() as i32,
            "{name}{mm}: one pattern per step"
        );
        assert_eq!(s.m.state().board.misreads, 0);
    }
}

/// Widths of the servo pulses on PA8 after `t0`: (falling-edge time, µs).
fn servo_pulses(s: &Session, t0: u64) -> Vec<(u64, f64)> {
    let ch = changes(s, PA, 8, t0);
    ch.windows(2)
        .filter(|w| w[0].1 && !w[1].1)
        .map(|w| (w[1].0, (w[1].0 - w[0].0) as f64 / T_PER_US as f64))
        .collect()
}

/// `$201=1`: PA8 carries 50 Hz pulses of 500 + angle x 2000/180 µs, the `$202` width
/// with the pen up and the `$203` width with it down; the pen moves only once the
/// steps before it are made, and the next move's first step comes `$204` ms (a lift)
/// or `$207` ms (a drop) after the pulse width changed (the servo's travel time), not
/// before.
#[test]
fn the_servo_pulse_is_202_or_203_wide_and_motion_waits_the_lift_time() {
    let mut s = board();
    for l in [
        "$201=1",
        "$202=120",
        "$203=45",
        "$204=300",
        "$207=250",
        "G21 G91 G1 F600",
    ] {
        ok(&mut s, l);
    }
    let up = 500.0 + 120.0 * 2000.0 / 180.0;
    let down = 500.0 + 45.0 * 2000.0 / 180.0;
    s.run_for(100 * T_PER_MS).unwrap();
    let p = servo_pulses(&s, 0);
    assert!(!p.is_empty(), "PA8 pulses (TIM1 with AOE)");
    let (t_last, w) = *p.last().unwrap();
    assert!((w - up).abs() < 1.5, "pen up: {w} µs, want {up}");
    let periods: Vec<f64> = p.windows(2).map(|w| ms(w[1].0 - w[0].0)).collect();
    assert!(
        periods.iter().all(|&ms| (ms - 20.0).abs() < 0.01),
        "50 Hz: {periods:?}"
    );
    let _ = t_last;
    for (cmd, want, wait_ms) in [("M3", down, 250.0), ("M5", up, 300.0), ("M3", down, 250.0)] {
        let t0 = s.now();
        ok(&mut s, "G1 X1");
        ok(&mut s, cmd);
        ok(&mut s, "G1 X1");
        s.wait_idle(20 * T_PER_S).unwrap();
        let steps: Vec<u64> =
            s.m.state()
                .board
                .steps
                .iter()
                .filter(|st| st.t > t0)
                .map(|st| st.t)
                .collect();
        assert_eq!(steps.len(), 160, "{cmd}");
        // The gap between the two moves is where the pen moved.
        let (gap_at, gap) = steps
            .windows(2)
            .map(|w| (w[0], w[1] - w[0]))
            .max_by_key(|g| g.1)
            .unwrap();
        let resume = gap_at + gap;
        let pulses = servo_pulses(&s, t0);
        let change = pulses
            .iter()
            .find(|p| (p.1 - want).abs() < 1.5)
            .unwrap_or_else(|| panic!("{cmd}: no pulse of {want} µs: {pulses:?}"));
        // The falling edge of the first new pulse, less its width: its rising edge.
        let rise = change.0 - (change.1 * T_PER_US as f64) as u64;
        eprintln!(
            "{cmd}: last step before {:.1} ms, new width from {:.1} ms, next step {:.1} ms",
            ms(gap_at),
            ms(rise),
            ms(resume)
        );
        assert!(
            rise > gap_at,
            "{cmd}: the pen moved before the stroke ended"
        );
        let wait = ms(resume - rise);
        assert!(
            (wait_ms - 20.0..=wait_ms + 25.0).contains(&wait),
            "{cmd}: motion resumed {wait:.1} ms after the servo pulse changed, want {wait_ms} ms ($204=300 lift, $207=250 drop)"
        );
    }
}

/// Limit/home switches at positions: `$H` homes both axes toward their `-` switches
/// and ends each axis the pull-off `$27` beyond its switch, the switches closed; with
/// `$21=1` a move across a switch at X 3 mm stops within a step of it with ALARM:1.
#[test]
fn homing_both_axes_onto_switches_at_positions_and_a_hard_limit() {
    let mut s = board();
    let mut o = s.m.state().board.outside.clone();
    o.switches = vec![
        PosSwitch::parse("x-:-5mm").unwrap(),
        PosSwitch::parse("y-:-3.5mm").unwrap(),
    ];
    s.set_outside(o);
    for l in ["$22=1", "$23=3", "$27=1"] {
        ok(&mut s, l);
    }
    let got = s.command("$H", 60 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "$H: {got:?}");
    // The locate and pull-off run at `$24` (25 mm/min by default): seconds.
    s.wait_idle(40 * T_PER_S).unwrap();
    let pos = s.m.state().board.pos;
    let mm = [pos[0] as f64 / STEPS_PER_MM, pos[1] as f64 / STEPS_PER_MM];
    eprintln!("homed at {mm:?} mm from power-up");
    assert!(
        (mm[0] - -4.0).abs() <= 0.05,
        "X pulled off 1 mm from its switch: {mm:?}"
    );
    assert!(
        (mm[1] - -2.5).abs() <= 0.05,
        "Y pulled off 1 mm from its switch: {mm:?}"
    );
    assert!(
        !s.m.state().board.pin(1, 1) && !s.m.state().board.pin(1, 3),
        "switches closed"
    );

    // A hard limit: a switch at X +3 mm from here.
    let mut o = s.m.state().board.outside.clone();
    let at = mm[0] + 3.0;
    o.switches = vec![PosSwitch::parse(&format!("x+:{at}mm")).unwrap()];
    s.set_outside(o);
    ok(&mut s, "$21=1");
    s.send(b"G21 G91 G1 F600 X10\n");
    let mut alarm = false;
    for _ in 0..300 {
        s.run_for(10 * T_PER_MS).unwrap();
        if s.received.contains("ALARM:1") {
            alarm = true;
            break;
        }
    }
    assert!(alarm, "ALARM:1 (got {:?})", s.received);
    s.run_for(200 * T_PER_MS).unwrap();
    let x = s.m.state().board.pos[0] as f64 / STEPS_PER_MM;
    eprintln!("hard limit: stopped at {x:.4} mm, switch at {at:.4} mm");
    assert!(
        x > at && x <= at + 2.0 / STEPS_PER_MM,
        "stopped within a step past the switch: {x}"
    );
}

/// The e-stop opened mid-move from the input schedule (as `--input 0.3s:estop=open`):
/// no step edge later than a step period after the pin edge, /EN off, ALARM:10, and
/// the buzzer (PA10) plays the alarm pattern: 300 ms on, 150 off, three times.
#[test]
fn the_estop_from_the_schedule_stops_at_once_and_the_buzzer_plays_the_alarm() {
    let mut s = board();
    ok(&mut s, "G21 G91 G1 F1200 X20");
    let t0 = s.now();
    s.inputs = Schedule::new(InputEvent::parse("300ms:estop=open").unwrap(), t0);
    s.run_for(2 * T_PER_S).unwrap();
    let edge = t0 + 300 * T_PER_MS;
    let last = s.m.state().board.steps.last().unwrap().t;
    assert!(
        last <= edge + 250 * T_PER_US,
        "a step {:.3} ms after the e-stop",
        ms(last - edge)
    );
    assert!(s.m.state().board.pin(PA, 9), "drivers off");
    assert!(s.received.contains("ALARM:10"), "{:?}", s.received);
    let beep = changes(&s, PA, 10, edge);
    let segs: Vec<f64> = beep.windows(2).map(|w| ms(w[1].0 - w[0].0)).collect();
    eprintln!(
        "buzzer after the e-stop: first on at +{:.1} ms, segments {segs:?}",
        ms(beep[0].0 - edge)
    );
    assert!(
        beep[0].1 && ms(beep[0].0 - edge) < 20.0,
        "the buzzer starts: {beep:?}"
    );
    assert_eq!(segs.len(), 5, "on, off, on, off, on: {segs:?}");
    for (got, want) in segs.iter().zip([300.0, 150.0, 300.0, 150.0, 300.0]) {
        assert!((got - want).abs() <= 5.0, "{segs:?}");
    }
}

/// Feed hold / SYNC (PB4) low mid-move stops the motion with a deceleration and holds
/// (`Hold`) while it stays low; high again resumes (the lab report's SYNC: a level
/// that pauses). A hold from `!` is resumed by a cycle-start pulse (PB5), and the move
/// ends where it was going. With `$215=1` the same from the inverted levels.
#[test]
fn sync_holds_and_cycle_start_resumes_from_the_pins_with_and_without_215() {
    for invert in [false, true] {
        let mut s = board();
        let case = format!("$215={}", u8::from(invert));
        let (active, idle) = if invert {
            ("high", "low")
        } else {
            ("low", "high")
        };
        if invert {
            // Inputs wired the other way: at rest the e-stop reads high, feed hold and
            // cycle start low. Rewired first (the board alarms: its e-stop reads
            // open), then `$215=1`, then a soft reset clears the alarm.
            let mut o = s.m.state().board.outside.clone();
            o.feed_hold_low = true;
            o.cycle_start_low = true;
            o.estop_open = true;
            s.set_outside(o);
            s.run_for(50 * T_PER_MS).unwrap();
            ok(&mut s, "$215=1");
            s.send(&[0x18]);
            s.run_for(300 * T_PER_MS).unwrap();
            ok(&mut s, "$X");
            let st = s.status().unwrap();
            assert_eq!(
                st.state, "Idle",
                "{case}: at rest with the inputs inactive: {:?} {}",
                s.received, st.pins
            );
        }
        ok(&mut s, "G21 G91 G1 F1200 X20");
        let t0 = s.now();
        let at = |ms: u64| t0 + ms * T_PER_MS;
        let script = format!(
            "200ms:hold={active}\n700ms:hold={idle}\n1500ms:start={active}\n1520ms:start={idle}\n"
        );
        s.inputs = Schedule::new(InputEvent::parse_script(&script).unwrap(), t0);
        s.run_to(at(650)).unwrap();
        let st = s.status().unwrap();
        assert!(
            st.state.starts_with("Hold"),
            "{case}: held by SYNC: {}",
            st.state
        );
        let held = s.m.state().board.steps.last().map_or(0, |st| st.t);
        assert!(
            held > at(200) && held < at(500),
            "{case}: decelerated to a stop: last step {:.1} ms",
            ms(held.saturating_sub(t0))
        );
        s.run_to(at(1000)).unwrap();
        let resumed =
            s.m.state()
                .board
                .steps
                .iter()
                .find(|st| st.t > at(700))
                .map(|st| st.t);
        assert!(
            resumed.is_some_and(|t| t < at(720)),
            "{case}: SYNC high again resumes: {resumed:?}"
        );
        s.send(b"!");
        s.run_to(at(1450)).unwrap();
        let n = s.m.state().board.steps.len();
        s.run_to(at(1500)).unwrap();
        assert_eq!(s.m.state().board.steps.len(), n, "{case}: held by `!`");
        s.run_to(at(1600)).unwrap();
        let restart =
            s.m.state()
                .board
                .steps
                .iter()
                .find(|st| st.t > at(1500))
                .map(|st| st.t);
        assert!(
            restart.is_some_and(|t| t < at(1520)),
            "{case}: the cycle-start pulse resumes: {restart:?}"
        );
        let mpos = rest_mpos(&mut s);
        assert_eq!(mpos[0], 1600, "{case}: the move ends where it was going");
        assert_eq!(s.m.state().board.pos[0], 1600, "{case}: the trace too");
    }
}

/// A glitch on the e-stop line (open for 2 µs mid-move: a flickering cable, interference): the
/// drivers go off at once as for any opening, and the user learns it: ALARM:10, never
/// a machine that says `Run` or `Idle` while its step output is halted for good.
#[test]
fn an_estop_glitch_alarms_rather_than_stalling_silently() {
    glitch_alarms_or_steps_on(&[], "estop", "ALARM:10");
}

/// The same for a hard limit (`$21=1`): a 2 µs glitch on the X limit line halts the
/// steps at once, and the machine says so with ALARM:1. (Before the fix both glitches
/// left the machine in `Run` with no step, for good.)
#[test]
fn a_limit_glitch_with_hard_limits_alarms_rather_than_stalling_silently() {
    glitch_alarms_or_steps_on(&["$21=1"], "limit-x", "ALARM:1\r");
}

/// A 2 µs open on `input` 300 ms into a 20 mm move (after `setup`): the board must
/// either report `alarm` or step on, never stall silently.
fn glitch_alarms_or_steps_on(setup: &[&str], input: &str, alarm: &str) {
    let mut s = board();
    for l in setup {
        ok(&mut s, l);
    }
    ok(&mut s, "G21 G91 G1 F1200 X20");
    let t0 = s.now();
    let mut ev = InputEvent::parse(&format!("300ms:{input}=open")).unwrap();
    ev.extend(InputEvent::parse(&format!("300.002ms:{input}=closed")).unwrap());
    s.inputs = Schedule::new(ev, t0);
    s.run_for(1000 * T_PER_MS).unwrap();
    let st = s.status().unwrap();
    let steps_after =
        s.m.state()
            .board
            .steps
            .iter()
            .filter(|st| st.t > t0 + 301 * T_PER_MS)
            .count();
    eprintln!(
        "after the glitch: {} with {steps_after} steps; received {:?}",
        st.state, s.received
    );
    assert!(
        s.received.contains(alarm) || steps_after > 0,
        "a silent stall: {} and no step after the glitch",
        st.state
    );
}

/// `$215=1` on a board still wired the usual way: the closed e-stop now reads pressed,
/// so the board alarms (ALARM:10) at once, as if it had been pressed, and after the
/// wiring is fixed, a reset and `$X` it draws again. Never a machine that accepts moves
/// and makes no step.
#[test]
fn inverting_the_inputs_under_a_closed_estop_alarms_and_never_stalls_silently() {
    let mut s = board();
    ok(&mut s, "$215=1");
    s.run_for(100 * T_PER_MS).unwrap();
    let st = s.status().unwrap();
    eprintln!("after $215=1: {} {:?}", st.state, s.received);
    // The wiring fixed: the inverted e-stop's switch released (high).
    let mut o = s.m.state().board.outside.clone();
    o.estop_open = true;
    o.feed_hold_low = true;
    o.cycle_start_low = true;
    s.set_outside(o);
    s.run_for(100 * T_PER_MS).unwrap();
    let unlock = s.command("$X", T_PER_S).unwrap();
    let st = s.status().unwrap();
    eprintln!("rewired, $X: {unlock:?} -> {}", st.state);
    if st.state == "Idle" {
        ok(&mut s, "G21 G91 G1 F1200 X2");
        s.run_for(500 * T_PER_MS).unwrap();
        let st = s.status().unwrap();
        let n = s.m.state().board.steps.len();
        assert!(
            n > 0,
            "a silent stall: the move was taken ({}) and no step came",
            st.state
        );
    }
}

/// `cargo emu run --pins OUT.csv --input ...` end to end: the CSV has a row for every
/// change of the wiring table's outputs (step pins, /EN, the LED and busy output, the
/// servo with its `PA8_us` widths), times in µs, and the SYNC input driven from the
/// command line holds the job (its job time grows by the hold).
#[test]
fn the_run_command_writes_the_pin_log_and_drives_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let prog = dir.path().join("job.nc");
    std::fs::write(
        &prog,
        "$201=1\n$203=45\nG21 G91 G1 F1200 X5\nM3\nG1 Y3\nM5\n",
    )
    .unwrap();
    let run = |extra: &[&str], csv: &std::path::Path| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_inkstep-emu"))
            .args([
                "run",
                prog.to_str().unwrap(),
                "--elf",
                common::elf().to_str().unwrap(),
            ])
            .args(["--log", dir.path().join("log").to_str().unwrap()])
            .args(["--pins", csv.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "{text}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let job: f64 = text
            .split("job time ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|t| t.parse().ok())
            .unwrap();
        (std::fs::read_to_string(csv).unwrap(), job)
    };
    let (csv, plain) = run(&[], &dir.path().join("a.csv"));
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(csv.lines().next(), Some("t_us,pin,value"));
    let count = |pin: &str| rows.iter().filter(|r| r[1] == pin).count();
    assert_eq!(count("PA0"), 2 * 400, "X's 400 pulses, both edges");
    assert_eq!(count("PA1"), 2 * 240, "Y's 240 pulses");
    assert!(
        count("PA9") >= 1 && count("PC13") >= 2 && count("PC15") >= 2,
        "{csv}"
    );
    let widths: Vec<f64> = rows
        .iter()
        .filter(|r| r[1] == "PA8_us")
        .map(|r| r[2].parse().unwrap())
        .collect();
    assert!(
        widths.iter().any(|w| (w - 1500.0).abs() < 1.5),
        "pen up 90°"
    );
    assert!(
        widths.iter().any(|w| (w - 1000.0).abs() < 1.5),
        "pen down 45°"
    );
    let times: Vec<f64> = rows.iter().map(|r| r[0].parse().unwrap()).collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]), "in time order");
    // SYNC low for 300 ms during the first move: the job takes that much longer.
    let (_, held) = run(
        &["--input", "150ms:hold=low", "--input", "450ms:hold=high"],
        &dir.path().join("b.csv"),
    );
    eprintln!("job {plain:.4} s, with a 300 ms SYNC hold {held:.4} s");
    assert!((held - plain - 0.3).abs() < 0.1, "{plain} -> {held}");
}

/// Play a `--keys` script on the board's key matrix (no LCD snapshots in it).
fn keys(s: &mut Session, script: &str) {
    inkstep_emu::demo::play(s, script, &std::env::temp_dir()).unwrap();
}

/// The buzzer's segments (on, off, on, ...) in ms from its first change after `t0`,
/// and when that first change came.
fn beep_segments(s: &Session, t0: u64) -> (Vec<f64>, Vec<(u64, bool)>) {
    let beep = changes(s, PA, 10, t0);
    let segs = beep.windows(2).map(|w| ms(w[1].0 - w[0].0)).collect();
    (segs, beep)
}

fn assert_pattern(what: &str, segs: &[f64], beep: &[(u64, bool)], want: &[f64]) {
    eprintln!("{what}: segments {segs:?} ms");
    assert!(
        beep.first().is_some_and(|b| b.1),
        "{what}: starts on: {beep:?}"
    );
    assert_eq!(segs.len(), want.len(), "{what}: {segs:?} against {want:?}");
    for (got, want) in segs.iter().zip(want) {
        assert!(
            (got - want).abs() <= 5.0,
            "{what}: {segs:?} against {want:?}"
        );
    }
}

/// The buzzer's other patterns (core/src/hmi/io.rs `Beep::pattern`), from the keypad:
/// a homing cycle asked from the machine menu with homing off (`$22=0`) is refused
/// with the error beep, two 80 ms beeps 80 ms apart; a star drawn from the menu ends
/// with the done beep, one 150 ms chirp, when its last step is out.
#[test]
fn the_buzzer_plays_the_error_and_done_patterns_from_the_keypad() {
    let mut s = board();
    // Past the boot screen, then 9 (Machine...) and 3 (Homing cycle).
    keys(&mut s, "wait:2000 9");
    let t0 = s.now();
    keys(&mut s, "3 wait:500");
    let (segs, beep) = beep_segments(&s, t0);
    assert!(
        ms(beep.first().map_or(0, |b| b.0) - t0) < 200.0,
        "the error beep comes with the key: {beep:?}"
    );
    assert_pattern("homing refused", &segs, &beep, &[80.0, 80.0, 80.0]);
    assert!(!s.m.state().board.pin(PA, 10), "silent after it");
    assert!(s.m.state().board.steps.is_empty(), "nothing moved");

    // Back to the menu, 6 (Star) of 5 mm, Enter on its preview: the star is drawn.
    keys(&mut s, "back wait:200 back wait:200 6 5 enter wait:200");
    let t0 = s.now();
    keys(&mut s, "enter wait:200 idle wait:500");
    let last = s.m.state().board.steps.last().map(|st| st.t).unwrap();
    assert!(last > t0, "the star was drawn");
    let (segs, beep) = beep_segments(&s, t0);
    let after = ms(beep.first().map_or(0, |b| b.0).saturating_sub(last));
    eprintln!("done beep {after:.1} ms after the last step");
    assert!(
        beep.first().is_some_and(|b| b.0 >= last) && after < 200.0,
        "the done beep follows the last step: {beep:?}"
    );
    assert_pattern("job done", &segs, &beep, &[150.0]);
}

/// `$5=1` inverts the limit pins: a switch wired normally open (the pin pulled high at
/// rest, pulled low while the axis is past it) is read as pressed when its pin is low.
/// The emulator's switches at positions are normally closed, so the same wiring is
/// made from them: a switch that is closed (low) up to a position and open (high)
/// beyond it, i.e. an `x+:P` switch, is at the axis's minus side a normally-open
/// switch at P (its pin falls as the axis goes below P). With `$5=1`: `$H` homes both
/// axes onto them and pulls off `$27`; with `$21=1` crossing one is a hard limit
/// (ALARM:1) within a step; with `$5=0` the same fall on the pin is a release and the
/// move runs to its end.
#[test]
fn inverted_limit_pins_home_and_trip_hard_limits_at_the_inverted_level() {
    let mut s = board();
    // The pins high at rest (the switches released, before `$5=1` they read open).
    let mut o = s.m.state().board.outside.clone();
    o.switches = vec![
        PosSwitch::parse("x+:-5mm").unwrap(),
        PosSwitch::parse("y+:-3.5mm").unwrap(),
    ];
    s.set_outside(o);
    for l in ["$5=1", "$22=1", "$23=3", "$27=1"] {
        ok(&mut s, l);
    }
    let got = s.command("$H", 60 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "$H with $5=1: {got:?}");
    // The locate and pull-off run at `$24` (25 mm/min by default): seconds.
    s.wait_idle(40 * T_PER_S).unwrap();
    let pos = s.m.state().board.pos;
    let mm = [pos[0] as f64 / STEPS_PER_MM, pos[1] as f64 / STEPS_PER_MM];
    eprintln!("homed with $5=1 at {mm:?} mm");
    assert!(
        (mm[0] - -4.0).abs() <= 0.05,
        "X 1 mm off its switch: {mm:?}"
    );
    assert!(
        (mm[1] - -2.5).abs() <= 0.05,
        "Y 1 mm off its switch: {mm:?}"
    );
    assert!(
        s.m.state().board.pin(1, 1) && s.m.state().board.pin(1, 3),
        "both pins high: released at the inverted level"
    );

    // A hard limit: moving X down across its switch (the pin falls at -5 mm).
    ok(&mut s, "$21=1");
    s.send(b"G21 G91 G1 F600 X-3\n");
    let mut alarm = false;
    for _ in 0..300 {
        s.run_for(10 * T_PER_MS).unwrap();
        if s.received.contains("ALARM:1") {
            alarm = true;
            break;
        }
    }
    assert!(alarm, "ALARM:1 with $5=1 (got {:?})", s.received);
    s.run_for(200 * T_PER_MS).unwrap();
    let x = s.m.state().board.pos[0] as f64 / STEPS_PER_MM;
    eprintln!("inverted hard limit: stopped at {x:.4} mm, switch at -5 mm");
    assert!(
        (-5.0 - 2.0 / STEPS_PER_MM..=-5.0).contains(&x),
        "stopped within a step past the switch: {x}"
    );

    // The same crossing with `$5=0` is a release (the pin falls): no alarm, the move
    // runs to its end.
    s.send(&[0x18]);
    s.run_for(300 * T_PER_MS).unwrap();
    ok(&mut s, "$X");
    ok(&mut s, "$21=0");
    ok(&mut s, "$5=0");
    ok(&mut s, "G21 G91 G1 F600 X3");
    s.wait_idle(10 * T_PER_S).unwrap();
    ok(&mut s, "$21=1");
    s.take_received();
    ok(&mut s, "G1 X-3");
    s.wait_idle(10 * T_PER_S).unwrap();
    assert!(!s.received.contains("ALARM"), "{:?}", s.received);
    let x2 = s.m.state().board.pos[0] as f64 / STEPS_PER_MM;
    assert!(
        (x2 - x).abs() < 0.02,
        "the move ran to its end: {x} -> {x2}"
    );
}

/// `$214` (axes with switches): with X only (`$214=1`) `$H` homes X onto its switch
/// and leaves Y where it is, though Y's switch is reachable; with no axis (`$214=0`)
/// `$H` is refused and nothing moves.
#[test]
fn homing_takes_only_the_axes_of_214() {
    let mut s = board();
    let mut o = s.m.state().board.outside.clone();
    o.switches = vec![
        PosSwitch::parse("x-:-5mm").unwrap(),
        PosSwitch::parse("y-:-3.5mm").unwrap(),
    ];
    s.set_outside(o);
    for l in ["$22=1", "$23=3", "$27=1", "$214=0"] {
        ok(&mut s, l);
    }
    let got = s.command("$H", 10 * T_PER_S).unwrap();
    eprintln!("$H with $214=0: {got:?}");
    assert!(got.contains("error:"), "refused: {got:?}");
    s.run_for(200 * T_PER_MS).unwrap();
    assert!(s.m.state().board.steps.is_empty(), "nothing moved");

    ok(&mut s, "$214=1");
    let got = s.command("$H", 60 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "$H: {got:?}");
    s.wait_idle(10 * T_PER_S).unwrap();
    let pos = s.m.state().board.pos;
    eprintln!("homed with $214=1 at {pos:?} steps");
    assert!(
        (pos[0] as f64 / STEPS_PER_MM - -4.0).abs() <= 0.05,
        "X homed: {pos:?}"
    );
    assert_eq!(pos[1], 0, "Y left alone");
    assert!(
        s.m.state().board.steps.iter().all(|st| st.pos[1] == 0),
        "Y never stepped"
    );
}

/// `$214` and hard limits: an axis left out of the mask has no switch, so its pin
/// (left floating, or picking up a stray switch) must not stop the machine, nor
/// appear in the status report's `Pn:`.
#[test]
fn a_limit_pin_of_an_axis_without_a_switch_is_no_hard_limit() {
    let mut s = board();
    ok(&mut s, "$214=1");
    ok(&mut s, "$21=1");
    ok(&mut s, "G21 G91 G1 F1200 X5");
    let t0 = s.now();
    s.inputs = Schedule::new(InputEvent::parse("150ms:limit-y=open").unwrap(), t0);
    let rest = s.wait_idle(10 * T_PER_S).unwrap();
    eprintln!(
        "Y's pin opened mid-move with $214=1: {:?} {rest}",
        s.received
    );
    // Nor is it shown as a tripped switch.
    assert!(!rest.contains("Pn:"), "{rest}");
    assert!(!s.received.contains("ALARM"), "{:?}", s.received);
    assert_eq!(s.m.state().board.pos[0], 400, "the move ran to its end");
    ok(&mut s, "G1 Y-1");
    s.wait_idle(10 * T_PER_S).unwrap();
    assert_eq!(s.m.state().board.pos[1], -80, "Y moves with its pin open");
}

/// The X steps of one `$H` of X alone (`$214=1`) onto a switch at -5 mm, split into
/// its four moves by direction: seek (-), back-off (+), locate (-), pull-off (+).
fn homing_phases(rates: (f64, f64, u32)) -> Vec<Vec<u64>> {
    let (feed, seek, debounce) = rates;
    let mut s = board();
    let mut o = s.m.state().board.outside.clone();
    o.switches = vec![PosSwitch::parse("x-:-5mm").unwrap()];
    s.set_outside(o);
    for l in [
        "$22=1".to_string(),
        "$23=1".into(),
        "$27=1".into(),
        "$214=1".into(),
        format!("$24={feed}"),
        format!("$25={seek}"),
        format!("$26={debounce}"),
    ] {
        ok(&mut s, &l);
    }
    let got = s.command("$H", 60 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "$H: {got:?}");
    s.wait_idle(10 * T_PER_S).unwrap();
    let mut phases: Vec<Vec<u64>> = Vec::new();
    let mut last = 0i32;
    let mut dir = 0i32;
    for st in &s.m.state().board.steps {
        let d = (st.pos[0] - last).signum();
        last = st.pos[0];
        if d != dir {
            phases.push(Vec::new());
            dir = d;
        }
        if let Some(p) = phases.last_mut() {
            p.push(st.t);
        }
    }
    assert_eq!(phases.len(), 4, "seek, back-off, locate, pull-off");
    phases
}

/// The rate of a phase's cruise (the median step interval), mm/min.
fn cruise_mm_per_min(t: &[u64]) -> f64 {
    let mut iv: Vec<u64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    iv.sort_unstable();
    let median = iv[iv.len() / 2] as f64 / T_PER_S as f64;
    60.0 / (median * STEPS_PER_MM)
}

/// `$25` (seek rate) times the fast search and the back-off, `$24` (locate feed) the
/// slow locate and the pull-off, each read from the step pin's edges at cruise; `$26`
/// (debounce) is the wait between the step that trips the switch and the first step
/// away from it, and between the locate's last step and the pull-off's first. Two
/// boards with the rates swapped round and debounce times 200 ms apart, and one whose
/// locate feed is below the start rate.
#[test]
fn homing_seeks_at_25_locates_at_24_and_waits_26_after_each_trip() {
    let mut seek_waits = Vec::new();
    // The third board locates below the start rate `$213` (60 mm/min): at its own feed.
    for (feed, seek, debounce) in [(80.0, 600.0, 40u32), (150.0, 300.0, 240), (40.0, 600.0, 40)] {
        let ph = homing_phases((feed, seek, debounce));
        let rates: Vec<f64> = ph.iter().map(|p| cruise_mm_per_min(p)).collect();
        let waits = [
            ms(ph[1][0] - ph[0][ph[0].len() - 1]),
            ms(ph[3][0] - ph[2][ph[2].len() - 1]),
        ];
        eprintln!(
            "$24={feed} $25={seek} $26={debounce}: rates {rates:.2?} mm/min, \
             waits after the trips {waits:.2?} ms, steps {:?}",
            ph.iter().map(|p| p.len()).collect::<Vec<_>>()
        );
        for (i, want) in [seek, seek, feed, feed].into_iter().enumerate() {
            assert!(
                (rates[i] - want).abs() <= want * 0.01,
                "phase {i}: {:.2} mm/min, want {want}",
                rates[i]
            );
        }
        // After each trip: the wait, then the next move's first step (the back-off at
        // `$25`, the pull-off at `$24`), which starts from rest: the pipeline's resume
        // wait and the start's lead, then the first period at the start rate `$213`
        // (60 mm/min) or its own feed if slower; the trip and the wait's end are seen
        // at the protocol's polls (15 ms of slack).
        let start_ms = f64::from(RESUME_MS) + f64::from(START_LEAD_MS);
        for (w, next) in waits.into_iter().zip([seek, feed]) {
            let first_step_ms = 60_000.0 / (next.min(60.0) * STEPS_PER_MM);
            assert!(
                w >= f64::from(debounce)
                    && w <= f64::from(debounce) + start_ms + first_step_ms + 15.0,
                "wait after a trip {w:.2} ms, $26={debounce}, start {start_ms} ms, \
                 first step {first_step_ms} ms"
            );
        }
        seek_waits.push(waits[0]);
    }
    // The same back-off start after both seeks: the waits differ by the $26 difference.
    let d = seek_waits[1] - seek_waits[0];
    assert!(
        (d - 200.0).abs() <= 3.0,
        "$26 240 vs 40: waits {d:.2} ms apart"
    );
}

/// `$208` (servo speed): at 120 deg/s the 60 deg from up (90) to down (30) are told to
/// the servo frame by frame, the pulse narrowing step by step over 0.5 s instead of
/// jumping, and the next stroke waits the turn plus the drop time `$207`.
#[test]
fn the_servo_turns_at_the_208_speed() {
    let mut s = board();
    for l in [
        "$201=1",
        "$202=90",
        "$203=30",
        "$207=100",
        "$208=120",
        "G21 G91 G1 F600",
    ] {
        ok(&mut s, l);
    }
    let up = 500.0 + 90.0 * 2000.0 / 180.0;
    let down = 500.0 + 30.0 * 2000.0 / 180.0;
    let t0 = s.now();
    ok(&mut s, "G1 X1");
    ok(&mut s, "M3");
    ok(&mut s, "G1 X1");
    s.wait_idle(20 * T_PER_S).unwrap();
    let steps: Vec<u64> = s.m.state().board.steps.iter().map(|st| st.t).collect();
    assert_eq!(steps.len(), 160);
    let pulses = servo_pulses(&s, t0);
    let turning: Vec<(u64, f64)> = pulses
        .iter()
        .copied()
        .filter(|p| p.1 < up - 1.5 && p.1 > down + 1.5)
        .collect();
    let first_down = pulses
        .iter()
        .find(|p| (p.1 - down).abs() < 1.5)
        .expect("the pen reaches down");
    let start = pulses
        .iter()
        .find(|p| p.1 < up - 1.5)
        .expect("the pulse narrows");
    // From the first narrowed pulse to the first at the down width: the turn, to
    // within a 20 ms frame either way.
    let turn = ms(first_down.0 - start.0);
    let resume = steps[80];
    eprintln!(
        "{} pulses between up and down, the turn {turn:.1} ms, next step {:.1} ms after the pen is down",
        turning.len(),
        ms(resume - first_down.0)
    );
    assert!(
        turning.windows(2).all(|w| w[1].1 <= w[0].1 + 0.5),
        "narrowing only: {turning:?}"
    );
    assert!(turning.len() >= 20, "step by step, not a jump: {turning:?}");
    assert!(
        (turn - 500.0).abs() <= 25.0,
        "60 deg at 120 deg/s: {turn:.1} ms"
    );
    // The drop time from the turn's end, seen at the next 20 ms frame at worst.
    let wait = ms(resume - first_down.0);
    assert!(
        (80.0..=145.0).contains(&wait),
        "the stroke waits the drop time $207=100 after the turn: {wait:.1} ms"
    );
}

/// `$100`-`$102` (steps per mm) and `$110`-`$112` (maximum rates) per axis, from the
/// step pins: a `G0` of 10 mm on each axis alone makes 10 x `$10n` pulses, and its
/// cruise (the median step interval) is the `$11n` rate.
#[test]
fn each_axis_steps_100_to_102_per_mm_and_rapids_at_110_to_112() {
    let mut s = board();
    let set = [(100.0, 900.0), (50.0, 1200.0), (250.0, 300.0)];
    for (axis, (per_mm, rate)) in set.iter().enumerate() {
        ok(&mut s, &format!("$10{axis}={per_mm}"));
        ok(&mut s, &format!("$11{axis}={rate}"));
    }
    ok(&mut s, "G21 G91");
    for (axis, (per_mm, rate)) in set.into_iter().enumerate() {
        let from = s.m.state().board.steps.len();
        let before = s.m.state().board.pos;
        ok(&mut s, &format!("G0 {}10", ["X", "Y", "Z"][axis]));
        s.wait_idle(20 * T_PER_S).unwrap();
        let b = &s.m.state().board;
        let t: Vec<u64> = b.steps[from..].iter().map(|st| st.t).collect();
        let mut iv: Vec<u64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        iv.sort_unstable();
        let cruise = 60.0 / (iv[iv.len() / 2] as f64 / T_PER_S as f64 * per_mm);
        eprintln!(
            "axis {axis}: {} pulses at $10{axis}={per_mm}, cruise {cruise:.2} mm/min at $11{axis}={rate}",
            t.len()
        );
        assert_eq!(t.len() as f64, 10.0 * per_mm, "axis {axis}: pulses");
        assert_eq!(
            b.pos[axis] - before[axis],
            (10.0 * per_mm) as i32,
            "axis {axis} alone, 10 mm"
        );
        assert!(
            (cruise - rate).abs() <= rate * 0.01,
            "axis {axis}: cruise {cruise:.2} mm/min, want {rate}"
        );
    }
}

/// `$20` with `$130`/`$131` (soft limits and travel): after `$H` onto switches at
/// positions, a move to inside the travel runs, one past `$130` is refused with
/// ALARM:2 before a single step, and a Y move past `$131` the same.
#[test]
fn soft_limits_refuse_a_move_past_130_or_131_before_any_step() {
    let mut s = board();
    let mut o = s.m.state().board.outside.clone();
    o.switches = vec![
        PosSwitch::parse("x-:-5mm").unwrap(),
        PosSwitch::parse("y-:-3.5mm").unwrap(),
    ];
    s.set_outside(o);
    for l in ["$22=1", "$23=3", "$27=1", "$130=20", "$131=15", "$20=1"] {
        ok(&mut s, l);
    }
    let got = s.command("$H", 60 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "$H: {got:?}");
    // The locate and pull-off run at `$24` (25 mm/min by default): seconds.
    s.wait_idle(40 * T_PER_S).unwrap();
    // Homed toward minus: the travel is [0, $130] x [0, $131] from the switches.
    ok(&mut s, "G21 G90 G53 G0 X19 Y14");
    let rest = s.wait_idle(10 * T_PER_S).unwrap();
    assert!(
        rest.contains("MPos:19.000,14.000"),
        "inside the travel: {rest}"
    );
    let inside = s.m.state().board.pos;
    for (line, axis) in [("G53 G0 X21", 0), ("G53 G0 Y16", 1)] {
        let steps = s.m.state().board.steps.len();
        s.send(format!("{line}\n").as_bytes());
        s.run_for(300 * T_PER_MS).unwrap();
        eprintln!("{line}: {:?}", s.received);
        assert!(s.received.contains("ALARM:2"), "{line}: {:?}", s.received);
        assert_eq!(s.m.state().board.steps.len(), steps, "{line}: no step");
        assert_eq!(s.m.state().board.pos, inside, "{line} (axis {axis})");
        s.received.clear();
        // Reset and unlock for the next one (the position is kept).
        s.send(&[0x18]);
        s.run_for(300 * T_PER_MS).unwrap();
        ok(&mut s, "$X");
        s.received.clear();
    }
}
