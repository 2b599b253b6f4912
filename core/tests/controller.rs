//! The controller wires protocol, keypad and HMI to one planner: G-code from USB and
//! keys from the matrix must both reach the planner through the machine state.

mod common;

use common::{drain, FakePlanner};
use inkstep_core::controller::Controller;
use inkstep_core::hmi::{MachineState, Page, BOOT_MS};
use inkstep_core::keypad::{Key, KEYMAP};
use inkstep_core::motion::Command;
use inkstep_core::motion::{Path, X};
use inkstep_core::settings::Settings;

/// Scan the matrix every 5 ms from `from` to `to` with `held` keys down.
fn scan(c: &mut Controller, m: &mut FakePlanner, held: &[Key], from: u32, to: u32) {
    let mut t = from;
    while t < to {
        let col = c.keypad().column();
        let mut rows = 0u8;
        for (r, row) in KEYMAP.iter().enumerate() {
            if held.contains(&row[col]) {
                rows |= 1 << r;
            }
        }
        c.key_scan(rows, m, t);
        c.poll(m, t);
        t += 5;
    }
}

fn text(c: &mut Controller) -> String {
    drain(c.protocol_mut())
}

#[test]
fn gcode_from_usb_reaches_the_planner() {
    let mut m = FakePlanner::new(16);
    let mut c = Controller::new(Settings::default(), 0);
    let line = b"G1 X1 F600\n";
    assert_eq!(c.usb_rx(line, &mut m, 0), line.len());
    c.poll(&mut m, 1);
    let out = text(&mut c);
    assert!(out.contains("Grbl 1.1h"), "{out}");
    assert!(out.ends_with("ok\r\n"), "{out}");
    let spmm = Settings::default().steps_per_mm(X);
    let x = spmm as i32; // X1 = one millimetre
    assert!(
        matches!(m.log.as_slice(), [Command::Move(mv)] if mv.target[X] == x),
        "{:?}",
        m.log
    );
}

#[test]
fn keypad_jog_moves_while_held_and_stops_on_release() {
    let mut m = FakePlanner::new(16);
    m.rate = 1; // one step per poll: the jog is still under way at release
    let mut c = Controller::new(Settings::default(), 0);
    scan(&mut c, &mut m, &[], 0, BOOT_MS + 100);
    // The boot screen has given way to the menu; '1' opens manual jog.
    assert!(
        matches!(c.hmi().page(), Page::Menu { .. }),
        "{:?}",
        c.hmi().page()
    );
    scan(
        &mut c,
        &mut m,
        &[Key::Digit(1)],
        BOOT_MS + 100,
        BOOT_MS + 300,
    );
    scan(&mut c, &mut m, &[], BOOT_MS + 300, BOOT_MS + 500);
    assert!(
        matches!(c.hmi().page(), Page::Jog(_)),
        "{:?}",
        c.hmi().page()
    );
    // Hold '6' (+X): a jog toward +X is queued and runs.
    let t0 = BOOT_MS + 500;
    for t in (t0..t0 + 300).step_by(5) {
        scan(&mut c, &mut m, &[Key::Digit(6)], t, t + 5);
        m.step();
    }
    let jog = m.log.iter().find_map(|cmd| match cmd {
        Command::Move(mv) if mv.path == Path::Line => Some(*mv),
        _ => None,
    });
    let jog = jog.expect("a jog move was queued");
    assert!(jog.target[X] > 1000, "{jog:?}");
    assert!(m.pos[X] > 0);
    assert_eq!(c.status(&m).state, MachineState::Jog);
    // Release: the jog is cancelled (held, then dropped).
    scan(&mut c, &mut m, &[], t0 + 300, t0 + 400);
    assert!(m.holding || m.clears > 0, "jog not stopped");
}

#[test]
fn settings_changes_reach_the_hmi() {
    let mut m = FakePlanner::new(16);
    let mut c = Controller::new(Settings::default(), 0);
    let line = b"$100=40\n";
    assert_eq!(c.usb_rx(line, &mut m, 0), line.len());
    c.poll(&mut m, 1);
    assert!(text(&mut c).ends_with("ok\r\n"));
    assert!(c.protocol_mut().machine_mut().take_settings_dirty());
    c.settings_changed();
    assert_eq!(c.hmi().config().steps_per_mm[X], 40.0);
}

/// The keypad's "set origin" makes the current X/Y zero and nothing else: the G-code
/// modal state (inch units, relative distances) and the feed override a sender set
/// stay, no welcome line is sent, and the next relative move starts from zero.
#[test]
fn keypad_set_origin_keeps_modal_state_and_overrides() {
    let mut m = FakePlanner::new(16);
    let mut c = Controller::new(Settings::default(), 0);
    scan(&mut c, &mut m, &[], 0, BOOT_MS + 100);
    let setup = b"G1 X10 Y5 F600\nG91 G20\n\x91";
    assert_eq!(c.usb_rx(setup, &mut m, BOOT_MS + 100), setup.len());
    c.poll(&mut m, BOOT_MS + 101);
    m.run_all();
    c.poll(&mut m, BOOT_MS + 102);
    assert_ne!(m.pos, [0, 0, 0]);
    let overrides = m.overrides;
    text(&mut c);
    // Main menu '9': the machine submenu; its '2': set origin here.
    let t = BOOT_MS + 200;
    scan(&mut c, &mut m, &[Key::Digit(9)], t, t + 200);
    scan(&mut c, &mut m, &[], t + 200, t + 400);
    scan(&mut c, &mut m, &[Key::Digit(2)], t + 400, t + 600);
    scan(&mut c, &mut m, &[], t + 600, t + 800);
    assert_eq!(&m.pos[..2], &[0, 0]);
    assert_eq!(m.overrides, overrides, "the feed override survives");
    assert_eq!(c.usb_rx(b"$G\n", &mut m, t + 800), 3);
    c.poll(&mut m, t + 801);
    let out = text(&mut c);
    assert!(!out.contains("Grbl 1.1h"), "no reset: {out}");
    assert!(
        out.contains("G20") && out.contains("G91"),
        "modal state kept: {out}"
    );
    // 0.1 inch relative from the new zero.
    assert_eq!(c.usb_rx(b"G1 X0.1 F20\n", &mut m, t + 900), 12);
    c.poll(&mut m, t + 901);
    let spmm = Settings::default().steps_per_mm(X);
    let want = (2.54 * spmm).round() as i32;
    assert!(
        matches!(m.log.last(), Some(Command::Move(mv)) if mv.target[X] == want),
        "{:?}",
        m.log.last()
    );
}
