//! The e-stop on the virtual board: its interrupt halts the steps at once through the
//! core's halt latch, and only the release rule lets them go again (the machine out of
//! alarm and the e-stop released), as on the board.

use inkstep_core::machine::PinLevels;
use inkstep_core::settings::Settings;
use inkstep_sim::board::{Board, StepEvent, PINS_AT_REST};

fn text(b: &mut Board) -> String {
    String::from_utf8(b.usb_read()).unwrap()
}

fn run_ms(b: &mut Board, ms: u64, ev: &mut Vec<StepEvent>) {
    let until = b.now() + Board::ms_to_ticks(ms);
    b.run_until(until, &mut |e| ev.push(e));
}

/// The answer to `?` (the protocol task takes the byte at once).
fn status(b: &mut Board, ev: &mut Vec<StepEvent>) -> String {
    text(b);
    b.usb_write(b"?");
    run_ms(b, 2, ev);
    let t = text(b);
    t.lines()
        .find(|l| l.starts_with('<'))
        .unwrap_or("")
        .to_string()
}

/// `bytes` from the host, then a few milliseconds; what the board answered.
fn send(b: &mut Board, bytes: &[u8], ev: &mut Vec<StepEvent>) -> String {
    text(b);
    assert_eq!(b.usb_write(bytes), bytes.len());
    run_ms(b, 20, ev);
    text(b)
}

const PRESSED: PinLevels = PinLevels {
    estop: true,
    ..PINS_AT_REST
};

#[test]
fn the_estop_halts_at_once_and_only_a_reset_after_its_release_frees_the_steps() {
    let mut b = Board::new(Settings::default());
    let mut ev = Vec::new();
    b.usb_write(b"G21 G90\nG1 X60 F3000\n");
    run_ms(&mut b, 300, &mut ev);
    assert!(status(&mut b, &mut ev).starts_with("<Run|"));
    let moved = ev.len();
    assert!(moved > 100, "{moved} steps before the e-stop");

    // Pressed: not one step more, and the alarm.
    b.set_pins(PRESSED);
    let at = b.pipeline.side().exec.position();
    assert!(b.is_halted());
    let n = ev.len();
    run_ms(&mut b, 500, &mut ev);
    assert_eq!(ev.len(), n, "a step after the e-stop");
    assert_eq!(b.pipeline.side().exec.position(), at);
    let st = status(&mut b, &mut ev);
    assert!(st.starts_with("<Alarm|"), "{st}");

    // A soft reset and `$X` while it is still pressed release nothing: still in
    // alarm, still halted, a move makes no step.
    let out = send(&mut b, b"\x18", &mut ev);
    assert!(out.contains("Grbl 1.1h"), "{out}");
    let out = send(&mut b, b"$X\nG1 X0 F3000\n", &mut ev);
    assert!(!out.contains("[MSG:Caution: Unlocked]"), "{out}");
    run_ms(&mut b, 300, &mut ev);
    assert!(b.is_halted());
    assert_eq!(b.pipeline.side().exec.position(), at);
    assert!(status(&mut b, &mut ev).starts_with("<Alarm|"));

    // Released (its interrupt fires on that edge too): still halted until the
    // machine is out of alarm.
    b.set_pins(PINS_AT_REST);
    run_ms(&mut b, 50, &mut ev);
    assert!(b.is_halted());
    assert!(status(&mut b, &mut ev).starts_with("<Alarm|"));
    send(&mut b, b"\x18", &mut ev);
    let out = send(&mut b, b"$X\n", &mut ev);
    assert!(out.contains("ok"), "{out}");
    assert!(
        !b.is_halted(),
        "released after the reset with the e-stop up"
    );
    assert!(status(&mut b, &mut ev).starts_with("<Idle|"));

    // Steps again, from where the e-stop stopped them (nothing queued before it runs).
    let n = ev.len();
    b.usb_write(b"G1 X0 F3000\n");
    assert!(b.run_to_idle(Board::ms_to_ticks(60_000), &mut |e| ev.push(e)));
    assert_eq!(
        ev.len() - n,
        at[0] as usize,
        "one step per step of the way back"
    );
    assert_eq!(b.pipeline.side().exec.position(), [0, 0, 0]);
}

#[test]
fn an_armed_hard_limit_halts_and_an_unarmed_one_does_not() {
    let mut s = Settings::default();
    s.set(21, 1.0).unwrap();
    let mut b = Board::new(s);
    let mut ev = Vec::new();
    b.usb_write(b"G21 G90\nG1 X60 F3000\n");
    run_ms(&mut b, 300, &mut ev);
    let hit = PinLevels {
        limits: [Some(true), Some(false), None],
        ..PINS_AT_REST
    };
    b.set_pins(hit);
    assert!(b.is_halted());
    let n = ev.len();
    run_ms(&mut b, 300, &mut ev);
    assert_eq!(ev.len(), n, "a step after the hard limit");
    let st = status(&mut b, &mut ev);
    assert!(st.starts_with("<Alarm|"), "{st}");

    // Without $21 the switch is only read (no halt).
    let mut b = Board::new(Settings::default());
    b.usb_write(b"G21 G90\nG1 X60 F3000\n");
    run_ms(&mut b, 300, &mut ev);
    b.set_pins(hit);
    assert!(!b.is_halted());
    let n = ev.len();
    run_ms(&mut b, 100, &mut ev);
    assert!(ev.len() > n, "unarmed: the motion goes on");
}
