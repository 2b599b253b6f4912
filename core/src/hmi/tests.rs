//! Key sequences driven through the HMI, asserting the actions it issues.

use super::*;
use crate::hmi::entry::FormKind;
use crate::keypad::{Keypad, KeypadConfig};
use core::f32::consts::PI;

struct Bench {
    hmi: Hmi,
    st: Snapshot,
    now: u32,
}

fn cfg() -> Config {
    Config::default() // 80 steps/mm on X and Y, 100 on Z, pen up 5 mm, down 0 mm
}

impl Bench {
    /// Past the boot screen, at the main menu, pen up at (0, 0).
    fn new() -> Self {
        let mut b = Bench {
            hmi: Hmi::new(cfg(), 0),
            st: Snapshot::idle_at([0, 0, 500]),
            now: 0,
        };
        b.now = BOOT_MS;
        b.tick();
        assert_eq!(b.hmi.page(), &Page::Menu { sel: 0 });
        b
    }

    fn ev(&mut self, key: Key, kind: KeyKind) -> std::vec::Vec<Action> {
        self.now += 20;
        self.hmi
            .key(KeyEvent { key, kind }, &self.st, self.now)
            .to_vec()
    }

    /// Press and release each key; collect everything issued.
    fn keys(&mut self, keys: &[Key]) -> std::vec::Vec<Action> {
        let mut all = std::vec::Vec::new();
        for k in keys {
            all.extend(self.ev(*k, KeyKind::Press));
            all.extend(self.ev(*k, KeyKind::Release));
        }
        all
    }

    /// Type a number ("-12.5") and press Enter.
    fn number(&mut self, s: &str) -> std::vec::Vec<Action> {
        let mut keys = std::vec::Vec::new();
        for c in s.chars() {
            keys.push(match c {
                '-' => Key::Sign,
                '.' => Key::Dot,
                d => Key::Digit(d.to_digit(10).unwrap() as u8),
            });
        }
        keys.push(Key::Enter);
        self.keys(&keys)
    }

    fn tick(&mut self) -> std::vec::Vec<Action> {
        self.now += 100;
        self.hmi.tick(&self.st, self.now).to_vec()
    }
}

fn moves(actions: &[Action]) -> std::vec::Vec<Move> {
    actions
        .iter()
        .filter_map(|a| match a {
            Action::Queue(m) => Some(*m),
            _ => None,
        })
        .collect()
}

fn d(n: u8) -> Key {
    Key::Digit(n)
}

#[test]
fn boot_screen_gives_way_to_the_menu_on_a_key() {
    let mut hmi = Hmi::new(cfg(), 0);
    let st = Snapshot::idle_at([0; 3]);
    assert_eq!(hmi.page(), &Page::Boot);
    assert!(hmi.tick(&st, 100).is_empty());
    assert_eq!(hmi.page(), &Page::Boot);
    hmi.key(
        KeyEvent {
            key: d(4),
            kind: KeyKind::Press,
        },
        &st,
        200,
    );
    assert_eq!(hmi.page(), &Page::Menu { sel: 0 });
}

#[test]
fn sine_mode_issues_a_sine_move_in_steps() {
    let mut b = Bench::new();
    b.keys(&[d(5)]);
    assert!(matches!(b.hmi.page(), Page::Form(f) if f.kind == FormKind::Sine));
    assert!(b.number("10").is_empty()); // A = 10 mm
    assert!(b.number("0.5").is_empty()); // w = 0.5 rad/mm
    assert!(b.number("90").is_empty()); // phi = 90 deg
    assert!(b.number("20").is_empty()); // length 20 mm
    let job = Job::Sine {
        amp: 10.0,
        omega: 0.5,
        phase: 90.0,
        len: 20.0,
    };
    assert_eq!(
        b.hmi.page(),
        &Page::Preview {
            job,
            form: Some(FormKind::Sine)
        }
    );
    let m = moves(&b.keys(&[Key::Enter]));
    assert_eq!(m.len(), 3);
    assert_eq!(m[0].target, [0, 0, 0], "pen down first");
    let Path::Sine { amp, omega, phase } = m[1].path else {
        panic!("expected a sine, got {:?}", m[1]);
    };
    assert_eq!(amp, 800.0); // 10 mm * 80 steps/mm
    assert!((omega - 0.5 / 80.0).abs() < 1e-9); // rad per X step
    assert!((phase - PI / 2.0).abs() < 1e-6);
    assert_eq!(m[1].target[0], 1600);
    assert_eq!(m[1].feed, Feed::MmPerMin(600.0));
    assert_eq!(
        m[2].target,
        [1600, m[1].target[1], 500],
        "pen up at the end"
    );
    assert!(matches!(b.hmi.page(), Page::Run(r) if r.phase == RunPhase::Running));
}

#[test]
fn line_mode_reaches_all_four_quadrants() {
    for (x, y, want) in [
        ("12.5", "7", [1000, 560]),
        ("-12.5", "7", [-1000, 560]),
        ("-12.5", "-7", [-1000, -560]),
        ("12.5", "-7", [1000, -560]),
    ] {
        let mut b = Bench::new();
        b.keys(&[d(2)]);
        b.number(x);
        b.number(y);
        let m = moves(&b.keys(&[Key::Enter]));
        assert_eq!(m[1].path, Path::Line);
        assert_eq!([m[1].target[0], m[1].target[1]], want, "dX {x} dY {y}");
    }
}

#[test]
fn arc_with_negative_angle_runs_clockwise() {
    let mut b = Bench::new();
    b.keys(&[d(3)]);
    b.number("10");
    b.number("-90");
    let m = moves(&b.keys(&[Key::Enter]));
    assert_eq!(
        m[1].path,
        Path::Arc {
            center: [-800, 0],
            ccw: false,
            turns: 0
        }
    );
    assert_eq!(m[1].target, [-800, -800, 0]);
}

#[test]
fn ellipse_and_star_modes_queue_their_paths() {
    let mut b = Bench::new();
    b.keys(&[d(4)]);
    b.number("20");
    b.number("10");
    let m = moves(&b.keys(&[Key::Enter]));
    assert_eq!(m.len(), 4, "pen down, two half ellipses, pen up");
    assert_eq!(
        m[1].path,
        Path::Ellipse {
            center: [-1600, 0],
            a: 1600,
            b: 800,
            ccw: true
        }
    );
    assert_eq!(m[2].target, [0, 0, 0]);

    let mut b = Bench::new();
    b.keys(&[d(6)]);
    b.number("40");
    let m = moves(&b.keys(&[Key::Enter]));
    assert_eq!(m.len(), 7);
    assert!(m[1..6].iter().all(|mv| mv.path == Path::Line));
    assert_eq!(m[5].target, [0, 0, 0], "the star closes on its top point");
}

#[test]
fn out_of_range_value_is_refused_with_a_message_and_a_beep() {
    let mut b = Bench::new();
    b.keys(&[d(3)]);
    let a = b.number("500");
    assert_eq!(a, [Action::Beep(Beep::Error)]);
    assert_eq!(
        b.hmi.toast().map(|t| t.as_str()),
        Some("R: 0.50..100.00 mm")
    );
    let Page::Form(f) = b.hmi.page() else {
        panic!()
    };
    assert_eq!(f.cur, 0, "stays on the bad field");
    // Fix it: backspace three times, type 25.
    b.keys(&[Key::Back, Key::Back, Key::Back]);
    b.number("25");
    let Page::Form(f) = b.hmi.page() else {
        panic!()
    };
    assert_eq!((f.cur, f.fields()[0].value), (1, 25.0));
}

#[test]
fn cancel_on_an_untouched_field_returns_to_the_menu() {
    let mut b = Bench::new();
    b.keys(&[d(5)]);
    b.keys(&[Key::Back]);
    assert_eq!(b.hmi.page(), &Page::Menu { sel: 4 });
}

#[test]
fn a_held_digit_through_the_real_keypad_enters_one_digit() {
    let mut b = Bench::new();
    b.keys(&[d(6)]); // star form
    let mut kp = Keypad::new(KeypadConfig::default());
    // Hold '3' (row 0, column 2) for two seconds with contact bounce at the start.
    for tick in 0..400u32 {
        let t = tick * 5;
        let col = kp.column();
        let bounce = t < 10 && tick % 2 == 1;
        let rows = if col == 2 && !bounce { 0b0001 } else { 0 };
        for ev in kp.feed(rows, t) {
            b.hmi.key(ev, &b.st, t);
        }
    }
    let Page::Form(f) = b.hmi.page() else {
        panic!()
    };
    assert_eq!(f.fields()[0].display().as_str(), "3");
}

#[test]
fn jog_moves_while_held_and_stops_on_release_speed_changes_once_per_press() {
    let mut b = Bench::new();
    b.keys(&[d(1)]);
    assert!(matches!(b.hmi.page(), Page::Jog(_)));
    let mut kp = Keypad::new(KeypadConfig::default());
    let mut issued = std::vec::Vec::new();
    // Hold '6' (+X: row 1, column 2) for 1 s, then hold 'A' (speed +: row 0, column
    // 3) for 1.5 s while still jogging, then let everything go.
    for tick in 0..700u32 {
        let t = tick * 5;
        let col = kp.column();
        let mut rows = 0;
        if t < 2500 && col == 2 {
            rows |= 0b0010;
        }
        if (1000..2500).contains(&t) && col == 3 {
            rows |= 0b0001;
        }
        b.st.state = if *b.hmi.page() == (Page::Menu { sel: 0 }) {
            MachineState::Idle
        } else {
            MachineState::Jog
        };
        for ev in kp.feed(rows, t) {
            issued.extend(b.hmi.key(ev, &b.st, t));
        }
    }
    let base = JOG_SPEEDS[JOG_SPEED_DEFAULT];
    let faster = JOG_SPEEDS[JOG_SPEED_DEFAULT + 1];
    assert_eq!(
        issued,
        [
            Action::JogStart {
                dir: [1, 0],
                feed_mm_min: base
            },
            Action::JogStart {
                dir: [1, 0],
                feed_mm_min: faster
            },
            Action::JogStop,
        ]
    );
    assert_eq!(b.hmi.jog_speed(), faster);
    let Page::Jog(j) = b.hmi.page() else { panic!() };
    assert_eq!((j.active, j.last_dir), (None, [1, 0]));
}

#[test]
fn jog_diagonal_and_switching_direction() {
    let mut b = Bench::new();
    b.keys(&[d(1)]);
    let a = b.ev(d(7), KeyKind::Press);
    assert_eq!(
        a,
        [Action::JogStart {
            dir: [-1, -1],
            feed_mm_min: 400.0
        }]
    );
    let a = b.ev(d(3), KeyKind::Press);
    assert_eq!(
        a,
        [
            Action::JogStop,
            Action::JogStart {
                dir: [1, 1],
                feed_mm_min: 400.0
            }
        ]
    );
    // Releasing the first key no longer stops the second direction.
    assert!(b.ev(d(7), KeyKind::Release).is_empty());
    assert_eq!(b.ev(Key::Back, KeyKind::Press), [Action::JogStop]);
    assert_eq!(b.hmi.page(), &Page::Menu { sel: 0 });
}

/// Start the default star job; returns its plan end.
fn start_star(b: &mut Bench) -> StepPos {
    b.keys(&[d(6), Key::Enter]);
    let m = moves(&b.keys(&[Key::Enter]));
    assert_eq!(m.len(), 7);
    m[6].target
}

#[test]
fn abort_mid_drawing_holds_clears_then_lifts_the_pen_where_it_stopped() {
    let mut b = Bench::new();
    start_star(&mut b);
    b.st = Snapshot {
        state: MachineState::Run,
        pos: [300, -900, 0],
        ..b.st
    };
    b.st.queue_empty = false;
    b.tick();
    assert_eq!(b.keys(&[Key::Back]), [Action::Abort]);
    assert!(matches!(b.hmi.page(), Page::Run(r) if r.phase == RunPhase::Stopping));
    // Still decelerating: nothing yet.
    b.st.state = MachineState::Hold;
    assert!(moves(&b.tick()).is_empty());
    // Stopped and flushed: pen up at the stop point, back to the menu, position shown.
    b.st = Snapshot {
        state: MachineState::Idle,
        pos: [320, -960, 0],
        queue_empty: true,
        ..b.st
    };
    let m = moves(&b.tick());
    assert_eq!(m.len(), 1);
    assert_eq!(m[0].target, [320, -960, 500]);
    assert_eq!(b.hmi.page(), &Page::Menu { sel: 0 });
    assert_eq!(
        b.hmi.toast().map(|t| t.as_str()),
        Some("Stopped X4.0 Y-12.0")
    );
}

#[test]
fn feed_hold_and_resume_with_enter() {
    let mut b = Bench::new();
    start_star(&mut b);
    b.st.state = MachineState::Run;
    b.st.queue_empty = false;
    assert_eq!(b.keys(&[Key::Enter]), [Action::FeedHold]);
    b.st.state = MachineState::Hold;
    assert_eq!(b.keys(&[Key::Enter]), [Action::Resume]);
}

#[test]
fn completion_beeps_and_reports_time_and_full_progress() {
    let mut b = Bench::new();
    let end = start_star(&mut b);
    let Page::Run(r) = b.hmi.page() else { panic!() };
    let t0 = r.started_ms;
    b.st = Snapshot {
        state: MachineState::Run,
        queue_empty: false,
        pos: [0, -1000, 0],
        ..b.st
    };
    assert_eq!(b.tick(), []);
    let Page::Run(r) = b.hmi.page() else { panic!() };
    assert!(r.progress() > 0.0 && r.progress() < 0.5);
    b.st = Snapshot {
        state: MachineState::Idle,
        queue_empty: true,
        pos: end,
        ..b.st
    };
    let a = b.tick();
    assert_eq!(a, [Action::Beep(Beep::Done)]);
    let Page::Run(r) = b.hmi.page() else { panic!() };
    assert_eq!(
        r.phase,
        RunPhase::Done {
            ms: b.now - t0,
            complete: true
        }
    );
    assert_eq!(r.progress(), 1.0);
    b.keys(&[Key::Enter]);
    assert_eq!(b.hmi.page(), &Page::Menu { sel: 0 });
    // Replay offers the same job again.
    b.keys(&[d(8)]);
    assert!(matches!(
        b.hmi.page(),
        Page::Preview {
            job: Job::Star { .. },
            form: None
        }
    ));
}

#[test]
fn a_job_that_stops_short_is_reported_after_settling() {
    let mut b = Bench::new();
    start_star(&mut b);
    b.st.pos = [10, 10, 0];
    b.tick();
    let mut beeps = std::vec::Vec::new();
    for _ in 0..12 {
        beeps.extend(b.tick());
    }
    assert_eq!(beeps, [Action::Beep(Beep::Error)]);
    assert!(matches!(
        b.hmi.page(),
        Page::Run(RunPage {
            phase: RunPhase::Done {
                complete: false,
                ..
            },
            ..
        })
    ));
}

#[test]
fn alarm_takes_over_once_unlock_then_back_to_menu() {
    let mut b = Bench::new();
    b.st.state = MachineState::Alarm(1);
    assert_eq!(b.tick(), [Action::Beep(Beep::Alarm)]);
    assert_eq!(b.hmi.page(), &Page::Alarm { code: 1 });
    assert!(b.tick().is_empty(), "one beep per alarm");
    assert_eq!(b.keys(&[Key::Enter]), [Action::Unlock]);
    b.st.state = MachineState::Idle;
    b.tick();
    assert_eq!(b.hmi.page(), &Page::Menu { sel: 0 });
}

#[test]
fn drawing_while_busy_or_in_alarm_is_refused() {
    let mut b = Bench::new();
    b.st.state = MachineState::Run; // e.g. a PC job streaming
    b.keys(&[d(6), Key::Enter]);
    assert_eq!(b.keys(&[Key::Enter]), [Action::Beep(Beep::Error)]);
    assert!(matches!(b.hmi.page(), Page::Error { title: "Busy", .. }));
    b.keys(&[Key::Enter]);
    b.st.state = MachineState::Alarm(2);
    b.tick();
    b.keys(&[Key::Back]);
    assert_eq!(b.keys(&[d(1)]), [Action::Beep(Beep::Error)]);
    assert!(matches!(b.hmi.page(), Page::Error { title: "Alarm", .. }));
}

#[test]
fn pen_toggle_origin_and_homing() {
    let mut b = Bench::new();
    b.st.pos = [800, 1600, 500];
    let m = moves(&b.keys(&[d(7)]));
    assert_eq!(m[0].target, [800, 1600, 0]);
    assert_eq!(b.hmi.toast().map(|t| t.as_str()), Some("Pen down"));
    b.st.pos[2] = 0;
    assert_eq!(moves(&b.keys(&[d(7)]))[0].target, [800, 1600, 500]);
    b.st.pos[2] = 500;

    b.keys(&[d(9)]);
    let m = moves(&b.keys(&[d(1)]));
    assert_eq!(m.len(), 2, "pen up, rapid travel; no pen down");
    assert_eq!(m[1].target, [0, 0, 500]);
    assert_eq!(m[1].feed, Feed::Rapid);
    let mut b = Bench::new();
    b.keys(&[d(9)]);
    assert_eq!(b.keys(&[d(2)]), [Action::SetOrigin]);
    assert_eq!(b.keys(&[d(3)]), [Action::Home]);
}

#[test]
fn status_page_adjusts_the_draw_feed_used_by_jobs() {
    let mut b = Bench::new();
    b.keys(&[d(0), Key::Up, Key::Up, Key::Back]);
    assert_eq!(b.hmi.draw_feed(), 700.0);
    b.keys(&[d(6), Key::Enter]);
    let m = moves(&b.keys(&[Key::Enter]));
    assert_eq!(m[1].feed, Feed::MmPerMin(700.0));
}

#[test]
fn feed_direction_history_keeps_the_latest_changes() {
    let mut b = Bench::new();
    for dir in [
        [1, 0],
        [1, 0],
        [0, 1],
        [-1, 1],
        [0, 0],
        [-1, -1],
        [1, 0],
        [0, -1],
        [1, 1],
    ] {
        b.st.dir = dir;
        b.tick();
    }
    let h: std::vec::Vec<[i8; 2]> = b.hmi.feed_dirs().copied().collect();
    assert_eq!(h, [[0, 1], [-1, 1], [-1, -1], [1, 0], [0, -1], [1, 1]]);
}

#[test]
fn new_settings_apply_to_the_next_job() {
    let mut b = Bench::new();
    b.hmi.set_config(Config {
        steps_per_mm: [40.0, 40.0, 100.0],
        draw_feed_mm_min: 900.0,
        ..cfg()
    });
    b.keys(&[d(2)]);
    b.number("10");
    b.number("0");
    let m = moves(&b.keys(&[Key::Enter]));
    assert_eq!(m[1].target, [400, 0, 0]);
    assert_eq!(m[1].feed, Feed::MmPerMin(900.0));
}
