//! The controller wires protocol, keypad and HMI to one planner: G-code from USB and
//! keys from the matrix must both reach the planner through the machine state.

mod common;

use common::flash::{CutFlash, STORE_RANGE};
use common::FakePlanner;
use inkstep_core::controller::{Controller, HostLink, Serviced, HOST_RX_RING, HOST_TX_RING};
use inkstep_core::halt::HaltLatch;
use inkstep_core::hmi::{Beep, MachineState, Page, BOOT_MS};
use inkstep_core::keypad::{Key, KEYMAP};
use inkstep_core::machine::{Inputs, MotionControl, PinLevels};
use inkstep_core::motion::Command;
use inkstep_core::motion::{Path, X};
use inkstep_core::ring::ByteRing;
use inkstep_core::settings::Settings;
use inkstep_core::settings_store::SettingsStore;

/// The pins at rest with the board's wiring: switches closed (low), the feed-hold and
/// cycle-start inputs released (high).
const AT_REST: PinLevels = PinLevels {
    estop: false,
    limits: [Some(false), Some(false), None],
    feed_hold: true,
    cycle_start: true,
};

/// The shell's side of the protocol tick, as the firmware's task and the simulator
/// have it: the host's byte rings, the pins, the port and the store.
struct Shell {
    rx: ByteRing<HOST_RX_RING>,
    tx: ByteRing<HOST_TX_RING>,
    pins: PinLevels,
    port_open: bool,
    store: SettingsStore<CutFlash>,
    halt: HaltLatch,
    now: u32,
}

impl Shell {
    /// A board whose flash holds `settings`, booted, with the host's port open.
    fn boot(settings: &Settings) -> (Shell, Controller) {
        let mut store = SettingsStore::new(CutFlash::new(), STORE_RANGE).unwrap();
        store.save_settings(settings).unwrap();
        let c = inkstep_core::in_place::build(|slot| Controller::boot_in(slot, &mut store, 0));
        let shell = Shell {
            rx: ByteRing::new(),
            tx: ByteRing::new(),
            pins: AT_REST,
            port_open: true,
            store,
            halt: HaltLatch::new(),
            now: 0,
        };
        (shell, c)
    }

    fn tick(&mut self, c: &mut Controller, m: &mut FakePlanner) -> Serviced {
        self.now += 1;
        self.service(c, m)
    }

    /// One call of the controller's service at `self.now`.
    fn service(&mut self, c: &mut Controller, m: &mut FakePlanner) -> Serviced {
        let clears = m.clears;
        let done = self.service_once(c, m);
        // The step side's flush tells the latch (the firmware's and the simulator's).
        if m.clears != clears {
            self.halt.flushed();
        }
        done
    }

    fn service_once(&mut self, c: &mut Controller, m: &mut FakePlanner) -> Serviced {
        let (_, mut rx) = self.rx.split();
        let (mut tx, _) = self.tx.split();
        let host = HostLink {
            rx: &mut rx,
            tx: &mut tx,
            port_open: self.port_open,
        };
        c.service(host, self.pins, &self.halt, &mut self.store, m, self.now)
    }

    /// The USB task's hand-over of a packet with a real-time byte, between two runs
    /// of the protocol task; returns what the host received.
    fn realtime(&mut self, c: &mut Controller, m: &mut FakePlanner) -> String {
        let (_, mut rx) = self.rx.split();
        let (mut tx, _) = self.tx.split();
        let host = HostLink {
            rx: &mut rx,
            tx: &mut tx,
            port_open: self.port_open,
        };
        c.take_realtime(host, m, self.now);
        self.read()
    }

    /// The protocol task at `t`, as the firmware runs it: service until no line may
    /// run in this period; returns what the host received.
    fn run(&mut self, c: &mut Controller, m: &mut FakePlanner, t: u32) -> String {
        self.now = t;
        let mut out = String::new();
        loop {
            let done = self.service(c, m);
            out += &self.read();
            if !done.again(t, t) {
                return out;
            }
        }
    }

    /// `bytes` from the host (all of them fit the receive ring).
    fn push(&mut self, bytes: &[u8]) {
        assert_eq!(self.rx.split().0.push(bytes), bytes.len());
    }

    /// `bytes` from the host, then ticks until everything is taken and answered.
    fn send(&mut self, c: &mut Controller, m: &mut FakePlanner, bytes: &[u8]) -> String {
        assert_eq!(self.rx.split().0.push(bytes), bytes.len());
        let mut out = String::new();
        for _ in 0..50 {
            self.tick(c, m);
            out += &self.read();
        }
        out
    }

    /// What the host has received.
    fn read(&mut self) -> String {
        let mut buf = [0u8; HOST_TX_RING];
        let mut out = String::new();
        loop {
            let n = self.tx.split().1.pop_into(&mut buf);
            if n == 0 {
                return out;
            }
            out += std::str::from_utf8(&buf[..n]).unwrap();
        }
    }
}

/// Scan the matrix every 5 ms from `from` to `to` with `held` keys down, the protocol
/// task running after each scan.
fn scan(sh: &mut Shell, c: &mut Controller, m: &mut FakePlanner, held: &[Key], from: u32, to: u32) {
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
        sh.run(c, m, t);
        t += 5;
    }
}

#[test]
fn gcode_from_usb_reaches_the_planner() {
    let mut m = FakePlanner::new(16);
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    sh.push(b"G1 X1 F600\n");
    let out = sh.run(&mut c, &mut m, 1);
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

/// A `?` that arrives with a line is answered by the USB task's hand-over at once,
/// before the protocol task runs the line (issue 20: the report does not wait for the
/// segment preparation and the next protocol run), and the line then runs as it
/// would have; the report is what the protocol task would have said at that point.
#[test]
fn a_status_request_is_answered_on_arrival_and_the_line_runs_after() {
    let mut m = FakePlanner::new(16);
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    let hello = sh.run(&mut c, &mut m, 1);
    assert!(hello.contains("Grbl 1.1h"), "{hello}");
    sh.push(b"G1 X1 F600\n?");
    sh.now = 2;
    let report = sh.realtime(&mut c, &mut m);
    assert!(
        report.starts_with("<Idle|MPos:0.000,0.000,0.000|Bf:16,117|"),
        "{report:?}"
    );
    assert!(m.log.is_empty(), "the line waits for the protocol task");
    let out = sh.run(&mut c, &mut m, 2);
    assert!(out.ends_with("ok\r\n") && !out.contains('<'), "{out:?}");
    assert_eq!(m.log.len(), 1, "{:?}", m.log);

    // The same bytes through the protocol task alone: the same report, then the ok.
    let mut m2 = FakePlanner::new(16);
    let (mut sh2, mut c2) = Shell::boot(&Settings::default());
    sh2.run(&mut c2, &mut m2, 1);
    sh2.push(b"G1 X1 F600\n?");
    let both = sh2.run(&mut c2, &mut m2, 2);
    assert_eq!(both, format!("{report}{out}"));
    assert_eq!(m2.log, m.log);
}

#[test]
fn keypad_jog_moves_while_held_and_stops_on_release() {
    let mut m = FakePlanner::new(16);
    m.rate = 1; // one step per poll: the jog is still under way at release
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    scan(&mut sh, &mut c, &mut m, &[], 0, BOOT_MS + 100);
    // The boot screen has given way to the menu; '1' opens manual jog.
    assert!(
        matches!(c.hmi().page(), Page::Menu { .. }),
        "{:?}",
        c.hmi().page()
    );
    scan(
        &mut sh,
        &mut c,
        &mut m,
        &[Key::Digit(1)],
        BOOT_MS + 100,
        BOOT_MS + 300,
    );
    scan(&mut sh, &mut c, &mut m, &[], BOOT_MS + 300, BOOT_MS + 500);
    assert!(
        matches!(c.hmi().page(), Page::Jog(_)),
        "{:?}",
        c.hmi().page()
    );
    // Hold '6' (+X): a jog toward +X is queued and runs.
    let t0 = BOOT_MS + 500;
    for t in (t0..t0 + 300).step_by(5) {
        scan(&mut sh, &mut c, &mut m, &[Key::Digit(6)], t, t + 5);
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
    scan(&mut sh, &mut c, &mut m, &[], t0 + 300, t0 + 400);
    assert!(m.holding || m.clears > 0, "jog not stopped");
}

#[test]
fn settings_changes_reach_the_hmi() {
    let mut m = FakePlanner::new(16);
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    sh.push(b"$100=40\n");
    assert!(sh.run(&mut c, &mut m, 1).ends_with("ok\r\n"));
    assert_eq!(c.hmi().config().steps_per_mm[X], 40.0);
}

/// The keypad's "set origin" makes the current X/Y zero and nothing else: the G-code
/// modal state (inch units, relative distances) and the feed override a sender set
/// stay, no welcome line is sent, and the next relative move starts from zero.
#[test]
fn keypad_set_origin_keeps_modal_state_and_overrides() {
    let mut m = FakePlanner::new(16);
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    scan(&mut sh, &mut c, &mut m, &[], 0, BOOT_MS + 100);
    sh.push(b"G1 X10 Y5 F600\nG91 G20\n\x91");
    sh.run(&mut c, &mut m, BOOT_MS + 101);
    m.run_all();
    sh.run(&mut c, &mut m, BOOT_MS + 102);
    assert_ne!(m.pos, [0, 0, 0]);
    let overrides = m.overrides;
    // Main menu '9': the machine submenu; its '2': set origin here.
    let t = BOOT_MS + 200;
    scan(&mut sh, &mut c, &mut m, &[Key::Digit(9)], t, t + 200);
    scan(&mut sh, &mut c, &mut m, &[], t + 200, t + 400);
    scan(&mut sh, &mut c, &mut m, &[Key::Digit(2)], t + 400, t + 600);
    scan(&mut sh, &mut c, &mut m, &[], t + 600, t + 800);
    assert_eq!(&m.pos[..2], &[0, 0]);
    assert_eq!(m.overrides, overrides, "the feed override survives");
    sh.push(b"$G\n");
    let out = sh.run(&mut c, &mut m, t + 801);
    assert!(!out.contains("Grbl 1.1h"), "no reset: {out}");
    assert!(
        out.contains("G20") && out.contains("G91"),
        "modal state kept: {out}"
    );
    // 0.1 inch relative from the new zero.
    sh.push(b"G1 X0.1 F20\n");
    sh.run(&mut c, &mut m, t + 901);
    let spmm = Settings::default().steps_per_mm(X);
    let want = (2.54 * spmm).round() as i32;
    assert!(
        matches!(m.log.last(), Some(Command::Move(mv)) if mv.target[X] == want),
        "{:?}",
        m.log.last()
    );
}

/// `$215` inverts the e-stop, feed-hold and cycle-start inputs (not only the e-stop):
/// the same pin levels read as active, and a released-level feed-hold pin holds
/// motion once inverted.
#[test]
fn setting_215_inverts_feed_hold_and_cycle_start_too() {
    let mut m = FakePlanner::new(16);
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    sh.tick(&mut c, &mut m);
    assert_eq!(c.protocol().machine().inputs(), Inputs::default());
    // With $215=1 the same pins at rest read as all three inputs active.
    let mut s = Settings::default();
    s.set(215, 1.0).unwrap();
    let (mut sh, mut c) = Shell::boot(&s);
    sh.tick(&mut c, &mut m);
    let i = c.protocol().machine().inputs();
    assert!(i.estop && i.feed_hold && i.cycle_start, "{i:?}");
    // Wired for the inversion: the e-stop pin high (released), feed hold and cycle
    // start low (released)...
    let (mut sh, mut c) = Shell::boot(&s);
    sh.pins.estop = true;
    sh.pins.feed_hold = false;
    sh.pins.cycle_start = false;
    sh.tick(&mut c, &mut m);
    assert_eq!(c.protocol().machine().inputs(), Inputs::default());
    m.rate = 1;
    sh.send(&mut c, &mut m, b"G1 X10 F600\n");
    assert!(m.is_moving());
    // ...and a high feed-hold pin is a hold.
    sh.pins.feed_hold = true;
    sh.tick(&mut c, &mut m);
    let i = c.protocol().machine().inputs();
    assert!(i.feed_hold && !i.cycle_start && !i.estop, "{i:?}");
    assert!(m.holding, "the inverted feed-hold pin holds motion");
    // The same levels through the interrupt path.
    sh.pins.feed_hold = false;
    sh.pins.cycle_start = true;
    c.set_pins(sh.pins, &mut m, sh.now);
    assert!(c.protocol().machine().inputs().cycle_start);
    assert!(!m.holding, "released and cycle start: resumed");
}

/// A soft reset right after `$215=1` (the e-stop rewired the other way, so that its
/// pin now reads released) clears the e-stop alarm: the new polarity applies to the
/// levels in the run that changed it, not at the next run, which a real-time byte
/// handled in between would not wait for (the image's pins test met it).
#[test]
fn a_reset_right_after_215_reads_the_inputs_with_the_new_polarity() {
    let mut m = FakePlanner::new(16);
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    // Wired for the inversion before the setting: the e-stop pin high reads pressed.
    sh.pins.estop = true;
    sh.pins.feed_hold = false;
    sh.pins.cycle_start = false;
    sh.tick(&mut c, &mut m);
    assert!(c.protocol().machine().inputs().estop);
    sh.push(b"$215=1\n");
    sh.now += 1;
    sh.service(&mut c, &mut m);
    let out = sh.read();
    assert!(out.contains("ok"), "{out:?}");
    // The reset comes before the protocol task's next call (the firmware's shell
    // lets the USB task run between two calls of one run).
    sh.push(&[0x18]);
    let out = sh.realtime(&mut c, &mut m);
    assert!(!out.contains("ALARM:10"), "{out:?}");
    let out = sh.send(&mut c, &mut m, b"$X\n");
    assert!(out.contains("ok") && !out.contains("error"), "{out:?}");
}

/// A save that fails is reported to the sender after the `ok` (which has gone out
/// when the save runs, at rest): the setting is in force until power-off.
#[test]
fn a_failed_settings_save_is_reported_to_the_sender() {
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    let mut m = FakePlanner::new(16);
    let mut flash = sh.store.into_flash();
    flash.cut_at = Some(flash.ops); // the next write or erase fails, and all after it
    sh.store = SettingsStore::new(flash, STORE_RANGE).unwrap();
    let out = sh.send(&mut c, &mut m, b"$100=100\n");
    assert!(
        out.ends_with("ok\r\n[MSG:Settings not saved: flash write failed]\r\n"),
        "{out:?}"
    );
    assert_eq!(c.protocol().machine().settings().steps_per_mm(X), 100.0);
    let out = sh.send(&mut c, &mut m, b"G10 L2 P1 X5\n");
    assert!(
        out.contains("[MSG:Offsets not saved: flash write failed]"),
        "{out:?}"
    );
}

/// Settings, offsets and startup lines go to flash, and only at rest (flash writes
/// stall the CPU); a later boot from the same flash has them.
#[test]
fn changes_are_saved_at_rest_and_survive_a_reboot() {
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    let mut m = FakePlanner::new(16);
    m.rate = 1;
    sh.send(
        &mut c,
        &mut m,
        b"$110=1234\n$N0=G21\nG1 X1 F600\nG10 L2 P1 X5\n",
    );
    assert!(m.is_moving());
    sh.tick(&mut c, &mut m);
    let (coords, _) = sh.store.load_coords();
    assert_eq!(coords.wcs[0][X], 0, "nothing written while moving");
    m.run_all();
    sh.tick(&mut c, &mut m);
    let (coords, _) = sh.store.load_coords();
    assert_eq!(coords.wcs[0][X], 5_000_000, "5 mm in nanometres");
    let mut store = sh.store;
    let c2 = inkstep_core::in_place::build(|slot| Controller::boot_in(slot, &mut store, 0));
    assert_eq!(c2.protocol().machine().settings().max_rate(X), 1234.0);
    assert_eq!(c2.protocol().startup_line(0), Some("G21"));
}

/// Opening the port starts a session: the welcome line, and in alarm how to unlock
/// (as after a reset); while the port is closed nothing is kept for the host.
#[test]
fn opening_the_port_sends_the_welcome_and_in_alarm_the_unlock_hint() {
    let mut s = Settings::default();
    s.set(22, 1.0).unwrap(); // homing enabled: the machine starts locked
    let (mut sh, mut c) = Shell::boot(&s);
    let mut m = FakePlanner::new(16);
    sh.port_open = false;
    for _ in 0..5 {
        sh.tick(&mut c, &mut m);
    }
    assert_eq!(sh.read(), "", "nobody listens: nothing kept");
    sh.port_open = true;
    let out = sh.send(&mut c, &mut m, b"");
    assert_eq!(
        out,
        "\r\nGrbl 1.1h ['$' for help]\r\n[MSG:'$H'|'$X' to unlock]\r\n"
    );
    // Unlocked, a reopened port gets the welcome alone.
    sh.send(&mut c, &mut m, b"$X\n");
    sh.port_open = false;
    sh.tick(&mut c, &mut m);
    sh.port_open = true;
    assert_eq!(
        sh.send(&mut c, &mut m, b""),
        "\r\nGrbl 1.1h ['$' for help]\r\n"
    );
    // A reset in alarm says it too.
    m.rate = 1;
    sh.send(&mut c, &mut m, b"G1 X10 F600\n");
    let out = sh.send(&mut c, &mut m, b"\x18");
    assert!(
        out.ends_with("ALARM:3\r\n\r\nGrbl 1.1h ['$' for help]\r\n[MSG:'$H'|'$X' to unlock]\r\n"),
        "{out:?}"
    );
}

/// A corrupt store's notice waits until the host listens, after the welcome.
#[test]
fn the_power_up_notice_waits_for_the_host() {
    let mut flash = CutFlash::new();
    flash.mem.fill(0x00); // not erased, not a store: corrupt
    let mut store = SettingsStore::new(flash, STORE_RANGE).unwrap();
    let mut c = inkstep_core::in_place::build(|slot| Controller::boot_in(slot, &mut store, 0));
    let mut sh = Shell {
        rx: ByteRing::new(),
        tx: ByteRing::new(),
        pins: AT_REST,
        port_open: false,
        store,
        halt: HaltLatch::new(),
        now: 0,
    };
    let mut m = FakePlanner::new(16);
    sh.tick(&mut c, &mut m);
    assert_eq!(sh.read(), "");
    sh.port_open = true;
    assert_eq!(
        sh.send(&mut c, &mut m, b""),
        "\r\nGrbl 1.1h ['$' for help]\r\n[MSG:Stored data corrupt, defaults restored]\r\n"
    );
}

/// The protocol tick leaves the HMI's beep and busy LED to the keypad task (which
/// plays the buzzer): a completion beep raised during the tick is still there.
#[test]
fn the_completion_beep_survives_the_protocol_tick() {
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    let mut m = FakePlanner::new(16);
    for _ in 0..(BOOT_MS + 100) {
        sh.tick(&mut c, &mut m);
    }
    let t = sh.now;
    // The star: '6', Enter (preview), Enter (draw).
    scan(&mut sh, &mut c, &mut m, &[Key::Digit(6)], t, t + 200);
    scan(&mut sh, &mut c, &mut m, &[], t + 200, t + 400);
    scan(&mut sh, &mut c, &mut m, &[Key::Enter], t + 400, t + 600);
    scan(&mut sh, &mut c, &mut m, &[], t + 600, t + 800);
    scan(&mut sh, &mut c, &mut m, &[Key::Enter], t + 800, t + 1000);
    scan(&mut sh, &mut c, &mut m, &[], t + 1000, t + 1200);
    assert!(!m.queue.is_empty(), "the star is queued");
    sh.now = t + 1200;
    let _ = c.take_outputs();
    sh.tick(&mut c, &mut m);
    m.run_all();
    for _ in 0..10 {
        sh.tick(&mut c, &mut m);
    }
    assert_eq!(c.take_outputs().beep, Some(Beep::Done));
}

/// The firmware's protocol task sleeps while `quiet` holds: only once the boot screen,
/// the replies and the motion are done, never while a line waits or the machine moves;
/// bytes from the host end it.
#[test]
fn quiet_only_when_nothing_waits() {
    let mut m = FakePlanner::new(16);
    m.rate = 10;
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    assert!(
        !sh.tick(&mut c, &mut m).quiet,
        "the welcome and the boot screen"
    );
    let mut t = 0;
    while !sh.tick(&mut c, &mut m).quiet {
        sh.read();
        t += 1;
        assert!(t < 3_000, "never quiet at rest");
    }
    assert!(sh.read().is_empty() || c.protocol_mut().output_len() == 0);
    sh.rx.split().0.push(b"G1 X1 F600\n");
    let mut busy = 0;
    loop {
        let done = sh.tick(&mut c, &mut m);
        sh.read();
        m.step();
        if done.quiet {
            break;
        }
        busy += 1;
        assert!(busy < 3_000, "never quiet after the move");
    }
    assert!(busy > 5, "quiet while the move ran ({busy} ticks)");
    assert!(m.queue.is_empty(), "quiet with a move queued");
    assert_eq!(m.pos[X], Settings::default().steps_per_mm(X) as i32);
    // Half a line is framed and waits for the rest: quiet, nothing runs.
    sh.rx.split().0.push(b"G1 X2");
    let mut t = 0;
    while !sh.tick(&mut c, &mut m).quiet {
        t += 1;
        assert!(t < 10, "never quiet with half a line");
    }
    assert!(m.queue.is_empty() && sh.read().is_empty());
    // Its end runs it.
    sh.rx.split().0.push(b" F600\n");
    assert!(!sh.tick(&mut c, &mut m).quiet, "quiet with a whole line");
    while !m.queue.is_empty() || !sh.tick(&mut c, &mut m).quiet {
        sh.read();
        m.step();
    }
    assert_eq!(m.pos[X], 2 * Settings::default().steps_per_mm(X) as i32);
}

/// bCNC raises DTR, waits a second and throws away what came: the welcome is said
/// again ahead of the answer to its first byte. A sender that speaks at once (UGS,
/// cncjs) gets it once.
#[test]
fn a_sender_that_waited_after_opening_the_port_gets_the_welcome_again() {
    const WELCOME: &str = "\r\nGrbl 1.1h ['$' for help]\r\n";
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    let mut m = FakePlanner::new(16);
    sh.port_open = false;
    sh.tick(&mut c, &mut m);
    sh.port_open = true;
    assert_eq!(sh.send(&mut c, &mut m, b""), WELCOME);
    // One second passes; the host flushes its input (drops the welcome).
    for _ in 0..1000 {
        sh.tick(&mut c, &mut m);
    }
    assert_eq!(sh.read(), "");
    let out = sh.send(&mut c, &mut m, b"$I\n");
    assert!(out.starts_with(&format!("{WELCOME}[VER:1.1h")), "{out:?}");
    // Only the session's first byte.
    let out = sh.send(&mut c, &mut m, b"?");
    assert!(out.starts_with("<Idle|"), "{out:?}");

    // A quick sender: welcome once.
    sh.port_open = false;
    sh.tick(&mut c, &mut m);
    sh.port_open = true;
    sh.tick(&mut c, &mut m);
    let out = sh.read() + &sh.send(&mut c, &mut m, b"$I\n");
    assert_eq!(out.matches("Grbl 1.1h").count(), 1, "{out:?}");
}

/// A C8 (64 KB) does not run the image but is visibly alive: the alarm and the part
/// it needs on USB, every command that would unlock or move refused, the motors off,
/// the LED blinking its code.
#[test]
fn a_chip_with_too_little_flash_says_so_and_keeps_the_motors_off() {
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    c.check_chip(64);
    let mut m = FakePlanner::new(16);
    sh.port_open = false;
    sh.tick(&mut c, &mut m);
    sh.port_open = true;
    let out = sh.send(&mut c, &mut m, b"");
    assert_eq!(
        out,
        format!(
            "\r\nGrbl 1.1h ['$' for help]\r\n[MSG:{}]\r\n",
            inkstep_core::controller::WRONG_CHIP
        )
    );
    assert!(out.contains("STM32F103CB"));
    assert!(sh.send(&mut c, &mut m, b"?").starts_with("<Alarm|"));
    for (line, want) in [
        ("$X\n", "error:9"),
        ("$H\n", "error:9"),
        ("$100=100\n", "error:9"),
        ("$RST=*\n", "error:9"),
        ("G0 X10\n", "error:9"),
        ("$J=G91 X1 F100\n", "error:8"),
    ] {
        let out = sh.send(&mut c, &mut m, line.as_bytes());
        assert!(out.ends_with(&format!("{want}\r\n")), "{line:?}: {out:?}");
    }
    assert!(sh.send(&mut c, &mut m, b"\x18").contains("STM32F103CB"));
    assert!(m.log.is_empty(), "nothing queued");
    let lit = (0..2000)
        .map(|t| c.outputs_now(&m, 10_000 + t))
        .inspect(|l| assert!(!l.motors && !l.busy))
        .filter(|l| l.led)
        .count();
    assert!(
        (300..1000).contains(&lit),
        "a blink code, lit {lit} ms of 2000"
    );
    // A CB runs.
    let (_, mut cb) = Shell::boot(&Settings::default());
    cb.check_chip(128);
    assert!(cb.protocol().machine().refusal().is_none());
}

/// `$1`: the motors keep their power `$1` ms after the last motion, then are released;
/// the busy outputs follow the motion itself, with no host traffic.
#[test]
fn motors_are_released_step_idle_delay_after_the_motion_and_busy_clears_with_it() {
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    let mut m = FakePlanner::new(16);
    sh.send(&mut c, &mut m, b"$1=40\nG1 X10 F600\n");
    let t0 = sh.now;
    let l = c.outputs_now(&m, t0);
    assert!(l.motors && l.busy && l.led);
    m.run_all();
    let t1 = t0 + 1;
    let l = c.outputs_now(&m, t1);
    assert!(!l.busy && !l.led, "busy clears with the last step");
    let off = (t1..t1 + 1000).find(|&t| !c.outputs_now(&m, t).motors);
    assert_eq!(off, Some(t0 + 40), "released $1 = 40 ms after the motion");
    sh.send(&mut c, &mut m, b"$1=255\nG1 X0\n");
    m.run_all();
    assert!(
        (0..5000).all(|t| c.outputs_now(&m, sh.now + t).motors),
        "255 keeps them"
    );
    sh.send(&mut c, &mut m, b"$SLP\n");
    assert!(
        !c.outputs_now(&m, sh.now + 6000).motors,
        "$SLP releases them"
    );
}

/// The halt latch's release rule through the service: an e-stop whose interrupt comes
/// after the protocol task read the inputs is not undone, even with its pin up again
/// when the release reads it (a glitch); the next run shows it to the machine, and
/// the latch holds until the machine is out of alarm with the e-stop released.
#[test]
fn an_estop_after_the_inputs_were_read_is_not_undone() {
    let (mut sh, mut c) = Shell::boot(&Settings::default());
    let mut m = FakePlanner::new(16);
    m.rate = 1;
    sh.send(&mut c, &mut m, b"G1 X10 F600\n");
    assert!(m.is_moving());
    let done = sh.tick(&mut c, &mut m);
    // The e-stop's interrupt, after that run read the pins; released again at once.
    sh.halt.trip_estop();
    assert!(!sh.halt.release(done.allows_release(AT_REST)));
    assert!(sh.halt.is_halted());
    let done = sh.tick(&mut c, &mut m);
    assert!(done.alarmed, "the machine saw the e-stop");
    assert!(!m.is_moving(), "the queue was dropped");
    assert!(!sh.halt.release(done.allows_release(AT_REST)));
    // Out of alarm with the e-stop up: released.
    sh.send(&mut c, &mut m, b"\x18");
    sh.send(&mut c, &mut m, b"$X\n");
    let done = sh.tick(&mut c, &mut m);
    assert!(!done.alarmed);
    // Pressed when the release looks: held.
    let pressed = PinLevels {
        estop: true,
        ..AT_REST
    };
    assert!(!sh.halt.release(done.allows_release(pressed)));
    assert!(sh.halt.release(done.allows_release(AT_REST)));
    assert!(!sh.halt.is_halted());
}

/// The pen servo's pulse is handed out when it changes, not every run.
#[test]
fn the_servo_pulse_is_handed_out_once_per_change() {
    let mut s = Settings::default();
    s.set(201, 1.0).unwrap();
    let (mut sh, mut c) = Shell::boot(&s);
    let mut m = FakePlanner::new(16);
    let up = sh.tick(&mut c, &mut m).servo_pulse_us;
    assert!(up.is_some());
    assert_eq!(sh.tick(&mut c, &mut m).servo_pulse_us, None);
    assert_eq!(sh.tick(&mut c, &mut m).servo_pulse_us, None);
}
