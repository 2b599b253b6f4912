//! The pen on the real image (issue 24), watched on PA8 (TIM1 CH1, the servo's 50 Hz
//! pulse): `M3 S` puts the pulse between the up and down widths, a feed hold in the
//! middle of a stroke lifts the pen once XY stands and `~` drops it before XY moves
//! on, and a layered job from the host tool (`(MSG,pen N: name)` and `M6 TN` between
//! layers) runs through its pen changes, drawing what the simulator draws.

mod common;

use common::booted;
use inkstep_core::settings::Settings;
use inkstep_emu::clock::{T_PER_MS, T_PER_S};
use inkstep_emu::session::Session;
use inkstep_serial::sender::Flow;
use inkstep_sim::board::Board;

const PA: usize = 0;
/// Up (90 deg) and down (30 deg) widths at the default angles, us.
const UP_US: f64 = 1499.0;
const DOWN_US: f64 = 833.0;

fn ok(s: &mut Session, line: &str) {
    let got = s.command(line, 2 * T_PER_S).unwrap();
    assert!(got.contains("ok"), "{line}: {got:?}");
}

/// The servo pulses on PA8 so far: (rising edge time, width in us).
fn pulses(s: &mut Session) -> Vec<(u64, f64)> {
    let edges: Vec<(u64, bool)> =
        s.m.state()
            .board
            .pin_changes
            .iter()
            .filter(|c| c.1 == PA && c.2 == 8)
            .map(|c| (c.0, c.3))
            .collect();
    edges
        .windows(2)
        .filter(|w| w[0].1 && !w[1].1)
        .map(|w| (w[0].0, (w[1].0 - w[0].0) as f64 * 1000.0 / T_PER_MS as f64))
        .collect()
}

/// The width of the last pulse, us.
fn pulse_now(s: &mut Session) -> f64 {
    s.run_for(45 * T_PER_MS).unwrap();
    pulses(s).last().expect("the servo pulses").1
}

fn x_now(s: &mut Session) -> f64 {
    s.status().unwrap().pos.unwrap()[0]
}

/// A board with the servo pen, PA8 watched.
fn servo_board() -> Session<'static> {
    let mut s = booted(None);
    s.m.board().watch[PA] |= 1 << 8;
    ok(&mut s, "$201=1");
    s
}

#[test]
fn m3_s_sets_the_servo_pulse_between_up_and_down() {
    let mut s = servo_board();
    assert!((pulse_now(&mut s) - UP_US).abs() < 2.0, "up at boot");
    for (line, want) in [
        ("M3", DOWN_US),
        ("M3 S500", 1166.0),
        ("S250", 1333.0),
        ("S1000", DOWN_US),
        ("M5", UP_US),
    ] {
        ok(&mut s, line);
        s.wait_idle(5 * T_PER_S).unwrap();
        let got = pulse_now(&mut s);
        assert!((got - want).abs() < 2.0, "{line}: {got} us, want {want}");
    }
    // The Z pen ($201=0): M3 S500 halfway between $205 (0) and $206 (-2 mm).
    ok(&mut s, "$201=0");
    ok(&mut s, "M3 S500");
    s.wait_idle(5 * T_PER_S).unwrap();
    let z = s.status().unwrap().pos.unwrap()[2];
    assert_eq!(z, -1.0, "Z halfway down");
}

/// `!` mid-stroke: the pulse goes to the up width once XY stands (Hold:0) and stays
/// there; `~` brings the down width back and no step comes for the drop time
/// ($207, 150 ms by default); the stroke then ends where it should.
#[test]
fn a_hold_mid_stroke_lifts_the_servo_and_resume_drops_it_before_xy_moves() {
    let mut s = servo_board();
    ok(&mut s, "M3");
    ok(&mut s, "N7 G1 X30 F600");
    s.run_for(1500 * T_PER_MS).unwrap();
    assert!((pulse_now(&mut s) - DOWN_US).abs() < 2.0, "drawing");
    // The report names the line being drawn and the pen down.
    s.take_received();
    s.send(b"?");
    s.run_for(5 * T_PER_MS).unwrap();
    let report = s.take_received();
    assert!(
        report.contains("|Ln:7|") && report.contains("|A:S>"),
        "{report}"
    );
    s.send(b"!");
    s.run_for(500 * T_PER_MS).unwrap();
    assert_eq!(s.status().unwrap().state, "Hold:0");
    assert!((pulse_now(&mut s) - UP_US).abs() < 2.0, "lifted while held");
    let held_x = x_now(&mut s);
    s.run_for(1000 * T_PER_MS).unwrap();
    assert!((pulse_now(&mut s) - UP_US).abs() < 2.0, "still up");
    assert_eq!(x_now(&mut s), held_x, "nothing moved");
    let resumed = s.now();
    s.send(b"~");
    s.run_for(300 * T_PER_MS).unwrap();
    let first_step =
        s.m.state()
            .board
            .steps
            .iter()
            .find(|st| st.t > resumed)
            .map(|st| st.t)
            .expect("moving again");
    let waited = (first_step - resumed) as f64 / T_PER_MS as f64;
    assert!(
        (150.0..165.0).contains(&waited),
        "XY waited {waited} ms for the drop"
    );
    let down_at = pulses(&mut s)
        .iter()
        .find(|p| p.0 > resumed && (p.1 - DOWN_US).abs() < 2.0)
        .map(|p| p.0)
        .expect("down again");
    assert!(down_at < first_step, "the pen is down before XY moves");
    s.wait_idle(10 * T_PER_S).unwrap();
    assert_eq!(x_now(&mut s), 30.0);
}

/// The Z pen ($201=0, the default) on the image: `!` mid-stroke lifts Z to $205 (0)
/// once XY stands, before Hold:0; `~` takes it back to $206 (-2 mm) and only then does
/// XY move on; the stroke ends exactly where it should, the pen still down.
#[test]
fn a_hold_mid_stroke_lifts_the_z_pen_and_resume_lowers_it_before_xy_moves() {
    let mut s = booted(None);
    let spm = Settings::default().steps_per_mm(2);
    let down = (Settings::default().pen_z_down() * spm).round() as i32;
    ok(&mut s, "M3");
    ok(&mut s, "G1 X30 F600");
    s.run_for(1500 * T_PER_MS).unwrap();
    assert_eq!(s.status().unwrap().pos.unwrap()[2], -2.0, "drawing");
    s.send(b"!");
    s.run_for(800 * T_PER_MS).unwrap();
    let st = s.status().unwrap();
    assert_eq!(st.state, "Hold:0");
    let held = st.pos.unwrap();
    assert_eq!(held[2], 0.0, "Z up while held");
    s.run_for(1000 * T_PER_MS).unwrap();
    assert_eq!(s.status().unwrap().pos.unwrap(), held, "nothing moved");
    let resumed = s.now();
    s.send(b"~");
    s.wait_idle(10 * T_PER_S).unwrap();
    let steps = &s.m.state().board.steps;
    let after: Vec<[i32; 3]> = steps
        .iter()
        .filter(|st| st.t > resumed)
        .map(|st| st.pos)
        .collect();
    let xy = after
        .iter()
        .position(|p| p[..2] != after[0][..2])
        .expect("moving again");
    assert!(xy > 0);
    assert_eq!(after[xy - 1][2], down, "Z down before XY moves");
    assert!(
        after[xy..].iter().all(|p| p[2] == down),
        "down while drawing"
    );
    let end = s.status().unwrap().pos.unwrap();
    assert_eq!(end, [30.0, 0.0, -2.0]);
}

/// The host tool's output for a three-layer SVG (`inkstep-host svg
/// host/tests/data/svg-real/vpype--test_svg-misc-multilayer_by_attributes.svg
/// --scale 0.2`), with the pen-change place at the origin ($216-$218): each `M6`
/// holds the board at X0 Y0 with the pen up until cycle start, and the pen-down
/// steps are exactly the simulator's for the same job.
#[test]
fn a_layered_job_from_the_host_tool_runs_through_its_pen_changes() {
    let job = include_str!("data/layers.nc");
    let settings = [(201, 1.0), (216, 1.0), (217, 0.0), (218, 0.0)];
    let mut s = booted(None);
    s.m.board().watch[PA] |= 1 << 8;
    for (n, v) in settings {
        ok(&mut s, &format!("${n}={v}"));
    }
    // An operator who presses cycle start every half second, paused or not.
    let mut next_start = s.now() + 500 * T_PER_MS;
    let done = s
        .stream(job, Flow::CharCount(128), 120 * T_PER_S, |s| {
            if s.now() >= next_start {
                s.send(b"~");
                next_start = s.now() + 500 * T_PER_MS;
            }
            Ok(())
        })
        .unwrap();
    assert!(done.errors.is_empty() && done.alarms.is_empty(), "{done:?}");
    let limit = s.now() + 30 * T_PER_S;
    while s.status().unwrap().state != "Idle" {
        s.send(b"~");
        s.run_for(200 * T_PER_MS).unwrap();
        assert!(s.now() < limit, "not idle");
    }
    // The pen-down steps: a step is drawn when the pulse before it was the down one.
    let pulses = pulses(&mut s);
    let steps = s.m.state().board.steps.clone();
    let drawn: Vec<[i32; 3]> = steps
        .iter()
        .filter(|st| {
            let i = pulses.partition_point(|p| p.0 < st.t);
            i > 0 && (pulses[i - 1].1 - DOWN_US).abs() < 2.0
        })
        .map(|st| st.pos)
        .collect();
    // Twice at the pen-change place, with the pen up.
    let at_origin = steps.windows(2).filter(|w| w[1].pos == [0, 0, 0]).count();
    assert!(at_origin >= 3, "two pen changes and the park: {at_origin}");

    // The same job on the simulator, cycle start as soon as it holds.
    let mut cfg = Settings::default();
    for (n, v) in settings {
        cfg.set(n, v).unwrap();
    }
    let mut b = Board::new(cfg);
    let mut sim_drawn = Vec::new();
    let mut sim_out = Vec::new();
    // Lines as a character-counting sender sends them: only what the receive buffer
    // has room for, so that `~` is never stuck behind G-code.
    let mut lines = job.lines().map(|l| format!("{l}\n")).peekable();
    let mut unsent: Vec<u8> = Vec::new();
    let end = Board::ms_to_ticks(120_000);
    while b.now() < end && !(lines.peek().is_none() && unsent.is_empty() && b.is_idle()) {
        let room = b.ctl.protocol().rx_free();
        while let Some(l) = lines.next_if(|l| unsent.len() + l.len() + 8 < room) {
            unsent.extend_from_slice(l.as_bytes());
        }
        let n = b.usb_write(&unsent);
        unsent.drain(..n);
        let until = b.now() + Board::ms_to_ticks(1);
        b.run_until(until, &mut |e| {
            if e.servo_down {
                sim_drawn.push(e.pos)
            }
        });
        sim_out.extend(b.usb_read());
        if b.ctl.hmi().prompt().is_some() {
            b.usb_write(b"~");
        }
    }
    assert!(
        b.is_idle(),
        "the simulator finished: {} lines unsent, {:?}, prompt {:?}, {:?}",
        lines.count(),
        b.ctl.protocol().machine().state(&b.pipeline),
        b.ctl.hmi().prompt(),
        String::from_utf8_lossy(&sim_out)
    );
    assert!(
        sim_drawn.len() > 10_000,
        "{} pen-down steps",
        sim_drawn.len()
    );
    assert_eq!(drawn.len(), sim_drawn.len(), "pen-down steps");
    assert!(drawn == sim_drawn, "the same strokes, step by step");
}

/// `M0` after a `(MSG, ...)`: the pen lifts, the LCD shows the pause prompt with the
/// message (pixel for pixel what the core draws for it), and key D on the keypad
/// continues: the pen drops and the next stroke is drawn.
#[test]
fn m0_shows_its_prompt_on_the_lcd_and_key_d_continues() {
    use inkstep_core::hmi::{Config, Hmi, MachineState, Snapshot};
    use inkstep_core::screens::{framebuffer::FrameBuffer, Screens};
    use inkstep_emu::board::Outside;

    let mut s = servo_board();
    for line in [
        "M3",
        "G1 X5 F600",
        "(MSG, Check the ink)",
        "M0",
        "G1 X10",
        "M5",
    ] {
        ok(&mut s, line);
    }
    s.run_for(1500 * T_PER_MS).unwrap();
    assert_eq!(s.status().unwrap().state, "Hold:0");
    assert!((pulse_now(&mut s) - UP_US).abs() < 2.0, "up while paused");
    s.run_for(300 * T_PER_MS).unwrap();
    let mut hmi = Hmi::new(Config::default(), 0);
    hmi.set_prompt(Some((None, b"Check the ink")));
    let mut st = Snapshot::idle_at([0; 3]);
    st.state = MachineState::Hold;
    let mut fb = FrameBuffer::new();
    Screens::new().render(&hmi, &st, 0, &mut fb).unwrap();
    let lcd = &s.m.state().board.lcd;
    let differ = (0..64)
        .flat_map(|y| (0..128).map(move |x| (x, y)))
        .filter(|&(x, y)| lcd.pixel(x, y) != fb.pixel(x, y))
        .count();
    assert_eq!(differ, 0, "the LCD shows the pause prompt");

    // Key D: row 3, column 3 of the matrix.
    let held_at = s.now();
    s.set_outside(Outside {
        keys: vec![(3, 3)],
        ..Outside::default()
    });
    s.run_for(100 * T_PER_MS).unwrap();
    s.set_outside(Outside::default());
    s.wait_idle(10 * T_PER_S).unwrap();
    assert_eq!(x_now(&mut s), 10.0, "the next stroke drawn");
    let down_again = pulses(&mut s)
        .iter()
        .any(|p| p.0 > held_at && (p.1 - DOWN_US).abs() < 2.0);
    assert!(down_again, "the pen dropped again for it");
}

/// `M0` as the last line and `!` at rest: nothing is queued, the firmware's protocol
/// task may sleep at once, and the pen must be up all the same.
#[test]
fn a_pause_with_nothing_queued_lifts_the_pen_too() {
    let mut s = servo_board();
    for line in ["M3", "G1 X5 F600", "M0"] {
        ok(&mut s, line);
    }
    s.run_for(1500 * T_PER_MS).unwrap();
    assert_eq!(s.status().unwrap().state, "Hold:0");
    assert!((pulse_now(&mut s) - UP_US).abs() < 2.0, "up after M0");
    s.send(b"~");
    s.run_for(500 * T_PER_MS).unwrap();
    assert!((pulse_now(&mut s) - DOWN_US).abs() < 2.0, "down again");
    s.send(b"!");
    s.run_for(300 * T_PER_MS).unwrap();
    assert!(
        (pulse_now(&mut s) - UP_US).abs() < 2.0,
        "up after ! at rest"
    );
}
