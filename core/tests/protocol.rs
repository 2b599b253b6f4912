//! Protocol and machine-state behaviour seen from a sender: responses, real-time
//! commands, flow control, alarms, homing, jogging, check mode and settings.

mod common;

use common::{drain, send, Drive, FakePlanner};
use inkstep_core::machine::{Inputs, MotionControl, RunState};
use inkstep_core::motion::Command;
use inkstep_core::motion::{Feed, Move, Path};
use inkstep_core::protocol::{Protocol, RX_BUFFER_SIZE, WELCOME};
use inkstep_core::settings::Settings;

fn boot() -> (Protocol, FakePlanner) {
    let mut p = Protocol::new(Settings::default());
    let m = FakePlanner::new(16);
    let hello = drain(&mut p);
    assert_eq!(hello, format!("\r\n{WELCOME}\r\n"));
    (p, m)
}

fn moves(m: &FakePlanner) -> Vec<Move> {
    m.log
        .iter()
        .filter_map(|c| match c {
            Command::Move(mv) => Some(*mv),
            _ => None,
        })
        .collect()
}

#[test]
fn every_line_gets_ok_or_error() {
    let (mut p, mut m) = boot();
    let out = send(
        &mut p,
        &mut m,
        "G21 G90\r\nG1 X10 F600\nG1 X\n\n(comment)\nG1 Y5 ; tail\nQ1\n",
    );
    assert_eq!(
        out,
        "ok\r\n[MSG:Job started]\r\nok\r\nerror:2\r\nok\r\nok\r\nok\r\nerror:20\r\n"
    );
    let t: Vec<_> = moves(&m).iter().map(|mv| mv.target).collect();
    assert_eq!(t, [[800, 0, 0], [800, 400, 0]]);
    assert_eq!(moves(&m)[0].line, 0, "no N, no line number (Ln:)");
    send(&mut p, &mut m, "N42 G1 X0\n");
    assert_eq!(moves(&m)[2].line, 42, "N numbers label moves");
}

#[test]
fn status_report_fields_and_realtime_mid_line() {
    let (mut p, mut m) = boot();
    // '?' in the middle of a line is answered at once and not part of the line.
    let n = p.receive(b"G1 X1?0 F100", &mut m, 0);
    assert_eq!(n, 12);
    let status = drain(&mut p);
    // Five bytes of the line had arrived when the '?' came.
    assert_eq!(
        status,
        "<Idle|MPos:0.000,0.000,0.000|Bf:16,123|FS:0,0|WCO:0.000,0.000,0.000>\r\n"
    );
    let out = send(&mut p, &mut m, "\n");
    assert!(out.ends_with("ok\r\n"));
    assert_eq!(moves(&m)[0].target, [800, 0, 0]);
    let out = send(&mut p, &mut m, "?");
    assert_eq!(out, "<Run|MPos:0.000,0.000,0.000|Bf:15,128|FS:600,0>\r\n");
    m.step();
    let out = send(&mut p, &mut m, "?");
    assert!(out.starts_with("<Idle|MPos:10.000,0.000,0.000|"), "{out}");
}

/// The shell's USB task hands the protocol a packet at once when it holds a byte that
/// `is_realtime` names: exactly the bytes that act without entering the line.
#[test]
fn is_realtime_names_exactly_the_bytes_that_bypass_the_receive_buffer() {
    for b in 0..=255u8 {
        let (mut p, mut m) = boot();
        let before = p.rx_free();
        assert_eq!(p.receive(&[b], &mut m, 0), 1, "byte {b:#04x} taken");
        let buffered = p.rx_free() < before;
        assert_eq!(
            inkstep_core::protocol::is_realtime(b),
            !buffered,
            "byte {b:#04x}: real-time or into the receive buffer"
        );
    }
}

/// An arc's line is interpreted in one call and planned in the next, the shell's lock
/// released in between (issue 20: each half about half a millisecond on the board); a
/// `?` answered between them sees the line taken and not yet planned, and the arc
/// then runs as one block with its `ok`. A straight line is still one call.
#[test]
fn an_arc_line_is_planned_in_the_call_after_its_interpretation() {
    let (mut p, mut m) = boot();
    assert_eq!(send(&mut p, &mut m, "G21 G90 G1 F600\n"), "ok\r\n");
    let line = b"G2 X10 Y0 I5 J0\n";
    assert_eq!(p.receive(line, &mut m, 0), line.len());
    assert!(p.poll_one(&mut m, 0), "interpreted: call again at once");
    assert!(moves(&m).is_empty(), "not planned yet");
    assert_eq!(drain(&mut p), "");
    assert_eq!(p.receive(b"?", &mut m, 0), 1);
    let report = drain(&mut p);
    assert!(
        report.starts_with("<Idle|MPos:0.000,0.000,0.000|Bf:16,128|"),
        "{report:?}"
    );
    assert!(p.poll_one(&mut m, 0), "planned");
    assert!(drain(&mut p).ends_with("ok\r\n"));
    let arc = moves(&m);
    assert!(
        matches!(arc.as_slice(), [mv] if mv.target == [800, 0, 0] && !matches!(mv.path, Path::Line)),
        "{arc:?}"
    );
    // A straight line: interpreted and planned in one call.
    let line = b"G1 X0\n";
    assert_eq!(p.receive(line, &mut m, 0), line.len());
    assert!(p.poll_one(&mut m, 0));
    assert_eq!(moves(&m).len(), 2);
    assert_eq!(drain(&mut p), "ok\r\n");
}

#[test]
fn full_queue_applies_back_pressure_without_losing_bytes() {
    let (mut p, mut m) = boot();
    let mut text = String::new();
    for i in 1..=40 {
        text.push_str(&format!("G1 X{i} F1000\n"));
    }
    // Nothing executes: the planner fills, then the receive buffer, then input stops.
    let mut taken = 0;
    loop {
        let n = p.receive(&text.as_bytes()[taken..], &mut m, 0);
        p.poll(&mut m, 0);
        if n == 0 {
            break;
        }
        taken += n;
    }
    assert_eq!(m.queued(), 16);
    assert!(taken < text.len(), "input must stop when buffers are full");
    assert_eq!(p.rx_free(), 0);
    // '?' still works while the buffer is full.
    assert_eq!(p.receive(b"?", &mut m, 0), 1);
    let out = drain(&mut p);
    assert!(out.contains("<Run|") && out.contains("|Bf:0,0|"), "{out}");
    // Let it run; every line is executed exactly once, in order.
    let mut rest = &text.as_bytes()[taken..];
    let mut oks = out.matches("ok").count();
    for _ in 0..10_000 {
        m.step();
        p.poll(&mut m, 0);
        let n = p.receive(rest, &mut m, 0);
        rest = &rest[n..];
        oks += drain(&mut p).matches("ok").count();
        if rest.is_empty() && oks == 40 {
            break;
        }
    }
    assert_eq!(oks, 40);
    let xs: Vec<i32> = moves(&m).iter().map(|mv| mv.target[0]).collect();
    assert_eq!(xs, (1..=40).map(|i| i * 80).collect::<Vec<_>>());
}

#[test]
fn character_counting_sender_never_overflows() {
    // A sender that keeps at most RX_BUFFER_SIZE unacknowledged bytes in flight, as
    // Grbl's documentation describes.
    let (mut p, mut m) = boot();
    m.cap = 4;
    let lines: Vec<String> = (0..300)
        .map(|i| format!("G1 X{} Y{} F2000", i % 50, i % 7))
        .collect();
    let mut in_flight: std::collections::VecDeque<usize> = Default::default();
    let mut next = 0;
    let mut acks = 0;
    let mut pending = String::new();
    for _ in 0..100_000 {
        while next < lines.len() {
            let len = lines[next].len() + 1;
            if in_flight.iter().sum::<usize>() + len > RX_BUFFER_SIZE {
                break;
            }
            let bytes = format!("{}\n", lines[next]);
            let n = p.receive(bytes.as_bytes(), &mut m, 0);
            assert_eq!(n, bytes.len(), "a counting sender must never be refused");
            in_flight.push_back(len);
            next += 1;
        }
        p.poll(&mut m, 0);
        pending.push_str(&drain(&mut p));
        while let Some(i) = pending.find("\r\n") {
            let resp: String = pending.drain(..i + 2).collect();
            if resp.starts_with("ok") || resp.starts_with("error") {
                assert!(resp.starts_with("ok"), "{resp}");
                in_flight.pop_front();
                acks += 1;
            }
        }
        if acks == lines.len() {
            break;
        }
        m.step();
    }
    assert_eq!(acks, 300);
}

#[test]
fn hold_resume_keeps_position_and_reports_hold_states() {
    let (mut p, mut m) = boot();
    m.rate = 10;
    send(&mut p, &mut m, "G1 X10 F600\n");
    m.step();
    p.receive(b"!", &mut m, 0);
    p.receive(b"?", &mut m, 0);
    let out = drain(&mut p);
    assert!(
        out.starts_with("<Hold:1|MPos:0.125,"),
        "decelerating: {out}"
    );
    m.step();
    let out = send(&mut p, &mut m, "?");
    assert!(out.starts_with("<Hold:0|MPos:0.250,"), "{out}");
    for _ in 0..5 {
        m.step();
    }
    assert_eq!(m.pos[0], 20, "no step once at rest");
    send(&mut p, &mut m, "~");
    m.run_all();
    assert_eq!(m.pos, [800, 0, 0]);
    let out = send(&mut p, &mut m, "?");
    assert!(out.starts_with("<Idle|MPos:10.000,"), "{out}");
}

#[test]
fn feed_hold_input_pauses_while_active_and_cycle_start_input_resumes() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "G1 X10 F600\n");
    let held = Inputs {
        feed_hold: true,
        ..Inputs::default()
    };
    p.set_inputs(held, &mut m, 0);
    assert!(m.holding);
    assert!(send(&mut p, &mut m, "?").contains("|Pn:H"));
    p.set_inputs(Inputs::default(), &mut m, 0);
    assert!(!m.holding, "releasing SYNC resumes");
    send(&mut p, &mut m, "!");
    assert!(m.holding);
    p.set_inputs(
        Inputs {
            cycle_start: true,
            ..Inputs::default()
        },
        &mut m,
        0,
    );
    assert!(!m.holding);
}

#[test]
fn soft_reset_while_moving_raises_alarm_3_and_unlock_clears_it() {
    let (mut p, mut m) = boot();
    m.rate = 10;
    send(&mut p, &mut m, "G1 X10 F600\nG1 X20\n");
    m.step();
    let out = send(&mut p, &mut m, "\x18");
    assert_eq!(
        out,
        format!("ALARM:3\r\n\r\n{WELCOME}\r\n[MSG:'$H'|'$X' to unlock]\r\n"),
        "the welcome line in alarm says how to unlock, as Grbl's"
    );
    assert!(m.queue.is_empty());
    assert_eq!(send(&mut p, &mut m, "G0 X1\n"), "error:9\r\n");
    assert_eq!(
        send(&mut p, &mut m, "$X\n"),
        "[MSG:Caution: Unlocked]\r\nok\r\n"
    );
    // Position is the one reached, and new moves start from it.
    send(&mut p, &mut m, "G91 G0 X1\n");
    assert_eq!(moves(&m).last().unwrap().target, [90, 0, 0]);
}

#[test]
fn estop_stops_at_once_and_needs_release_reset_and_unlock() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "G1 X10 F600\n");
    let clears = m.clears;
    p.set_inputs(
        Inputs {
            estop: true,
            ..Inputs::default()
        },
        &mut m,
        0,
    );
    assert_eq!(m.clears, clears + 1);
    assert!(m.queue.is_empty());
    let out = drain(&mut p);
    assert_eq!(out, "ALARM:10\r\n[MSG:Reset to continue]\r\n");
    assert!(send(&mut p, &mut m, "$X\n").ends_with("error:9\r\n"));
    let out = send(&mut p, &mut m, "\x18");
    assert!(out.contains(WELCOME));
    assert!(
        !out.contains("to unlock"),
        "$X cannot unlock it while pressed"
    );
    assert!(
        send(&mut p, &mut m, "$X\n").ends_with("error:9\r\n"),
        "still pressed"
    );
    p.set_inputs(Inputs::default(), &mut m, 0);
    assert!(
        send(&mut p, &mut m, "$X\n").ends_with("error:9\r\n"),
        "reset still needed"
    );
    assert!(send(&mut p, &mut m, "\x18").ends_with("[MSG:'$H'|'$X' to unlock]\r\n"));
    assert_eq!(
        send(&mut p, &mut m, "$X\n"),
        "[MSG:Caution: Unlocked]\r\nok\r\n"
    );
    assert_eq!(p.machine().state(&m), RunState::Idle);
}

#[test]
fn hard_limit_alarm() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "$21=1\nG1 X10 F600\n");
    let hit = Inputs {
        limits: [true, false, false],
        ..Inputs::default()
    };
    p.set_inputs(hit, &mut m, 0);
    assert!(m.queue.is_empty());
    assert_eq!(drain(&mut p), "ALARM:1\r\n[MSG:Reset to continue]\r\n");
}

/// An axis left out of `$214` has no switch: its pin is no hard limit.
#[test]
fn hard_limits_only_on_axes_with_a_switch() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "$214=1\n$21=1\nG1 X10 F600\n");
    drain(&mut p);
    let y = Inputs {
        limits: [false, true, false],
        ..Inputs::default()
    };
    p.set_inputs(y, &mut m, 0);
    assert!(!m.queue.is_empty(), "the move goes on");
    assert!(!drain(&mut p).contains("ALARM"));
    let x = Inputs {
        limits: [true, true, false],
        ..Inputs::default()
    };
    p.set_inputs(x, &mut m, 0);
    assert!(m.queue.is_empty());
    assert_eq!(drain(&mut p), "ALARM:1\r\n[MSG:Reset to continue]\r\n");
}

/// `Pn:` names the limit pins of the axes with a switch (`$214`) only: the pin of an
/// axis without one is wired to nothing (it reads open), and no tripped switch.
#[test]
fn pn_shows_the_limit_pins_of_axes_with_a_switch_only() {
    let (mut p, mut m) = boot();
    let both = Inputs {
        limits: [true, true, false],
        ..Inputs::default()
    };
    p.set_inputs(both, &mut m, 0);
    let report = send(&mut p, &mut m, "?");
    assert!(report.contains("|Pn:XY"), "{report}");
    send(&mut p, &mut m, "$214=1\n");
    let report = send(&mut p, &mut m, "?");
    assert!(
        report.contains("|Pn:X") && !report.contains("Y"),
        "{report}"
    );
    send(&mut p, &mut m, "$214=0\n");
    let report = send(&mut p, &mut m, "?");
    assert!(!report.contains("Pn:"), "{report}");
    let held = Inputs {
        limits: [true, true, false],
        feed_hold: true,
        ..Inputs::default()
    };
    p.set_inputs(held, &mut m, 0);
    let report = send(&mut p, &mut m, "?");
    assert!(
        report.contains("|Pn:H"),
        "the other pins as before: {report}"
    );
}

#[test]
fn soft_limits_reject_before_any_step() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "$22=1\n$X\n$20=1\n");
    let out = send(&mut p, &mut m, "G0 X100\nG0 X400\n");
    assert_eq!(out, "[MSG:Job started]\r\nok\r\nALARM:2\r\nok\r\n");
    let t: Vec<_> = moves(&m).iter().map(|mv| mv.target[0]).collect();
    assert_eq!(t, [8000], "the target outside travel was never queued");
    assert_eq!(send(&mut p, &mut m, "G0 X1\n"), "error:9\r\n");
    // A jog outside Idle/Jog, in alarm too, is Grbl's error 8.
    assert!(send(&mut p, &mut m, "$J=G91 X-500 F100\n").ends_with("error:8\r\n"));
    // The move under way decelerates to rest, then the queue is dropped.
    m.step();
    p.poll(&mut m, 0);
    assert!(m.queue.is_empty());
    send(&mut p, &mut m, "$X\n");
    assert_eq!(send(&mut p, &mut m, "$J=G91 X-500 F100\n"), "error:15\r\n");
}

#[test]
fn homing_seeks_locates_pulls_off_and_sets_position() {
    let (mut p, mut m) = boot();
    m.rate = 8; // 0.1 mm per step() at 80 step/mm
    send(&mut p, &mut m, "$22=1\n$214=3\n");
    // Switches at X = -30 mm and Y = -20 mm (machine frame at power-up).
    let switch = |pos: [i32; 3]| [pos[0] <= -2400, pos[1] <= -1600, false];
    let out = send(&mut p, &mut m, "$H\n");
    assert_eq!(out, "ok\r\n");
    let mut t = 0;
    for _ in 0..100_000 {
        t += 1;
        m.step();
        let inputs = Inputs {
            limits: switch(m.pos),
            ..Inputs::default()
        };
        p.set_inputs(inputs, &mut m, t);
        p.poll(&mut m, t);
        if p.machine().state(&m) != RunState::Home {
            break;
        }
    }
    assert_eq!(p.machine().state(&m), RunState::Idle, "{}", drain(&mut p));
    assert_eq!(m.pos, [80, 80, 0], "pull-off of 1 mm inside travel");
    let out = send(&mut p, &mut m, "?");
    assert!(out.starts_with("<Idle|MPos:1.000,1.000,0.000|"), "{out}");
    // Slow locate ran at $24.
    assert!(moves(&m).iter().any(|mv| mv.feed == Feed::MmPerMin(25.0)));
}

#[test]
fn homing_fails_with_alarm_9_when_no_switch() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "$22=1\n$H\n");
    for t in 0..100 {
        m.step();
        p.poll(&mut m, t);
    }
    assert!(drain(&mut p).contains("ALARM:9"));
    assert_eq!(p.machine().state(&m), RunState::Alarm);
}

#[test]
fn jog_and_jog_cancel() {
    let (mut p, mut m) = boot();
    m.rate = 8;
    assert_eq!(send(&mut p, &mut m, "$J=G91 X10 F500\n"), "ok\r\n");
    assert_eq!(
        moves(&m)[0],
        Move {
            target: [800, 0, 0],
            path: Path::Line,
            feed: Feed::MmPerMin(500.0),
            line: 0
        }
    );
    m.step();
    assert!(send(&mut p, &mut m, "?").starts_with("<Jog|"));
    // G-code is locked out while jogging: Grbl's error 9.
    assert_eq!(send(&mut p, &mut m, "G1 X1 F10\n"), "error:9\r\n");
    send(&mut p, &mut m, "\u{85}");
    m.step();
    p.poll(&mut m, 0);
    assert!(m.queue.is_empty());
    assert!(
        send(&mut p, &mut m, "?").starts_with("<Idle|MPos:0.200,"),
        "one step to decelerate"
    );
    // The interpreter continues from where the jog stopped.
    send(&mut p, &mut m, "G91 G0 X1\n");
    assert_eq!(moves(&m).last().unwrap().target, [96, 0, 0]);
    assert_eq!(
        send(&mut p, &mut m, "$J=G91 X1 F10\n"),
        "error:8\r\n",
        "not while running"
    );
    m.run_all();
    assert_eq!(send(&mut p, &mut m, "$J=G1 X1 F10\n"), "error:16\r\n");
}

#[test]
fn check_mode_parses_without_moving() {
    let (mut p, mut m) = boot();
    assert_eq!(send(&mut p, &mut m, "$C\n"), "[MSG:Enabled]\r\nok\r\n");
    assert!(send(&mut p, &mut m, "?").starts_with("<Check|"));
    assert_eq!(
        send(&mut p, &mut m, "G1 X10 F100\nG2 X1\n"),
        "ok\r\nerror:35\r\n"
    );
    assert!(m.log.is_empty());
    let out = send(&mut p, &mut m, "$C\n");
    assert_eq!(out, format!("[MSG:Disabled]\r\nok\r\n\r\n{WELCOME}\r\n"));
}

#[test]
fn settings_listing_and_changes() {
    let (mut p, mut m) = boot();
    let out = send(&mut p, &mut m, "$$\n");
    assert!(out.starts_with("$0=10\r\n$1=25\r\n$2=0\r\n"));
    assert!(out.contains("$100=80.000\r\n"));
    assert!(out.ends_with("$218=0.000\r\nok\r\n"), "{out}");
    assert_eq!(
        send(
            &mut p,
            &mut m,
            "$100=100\n$100=-1\n$0=1\n$999=1\n$Q\n$20=1\n"
        ),
        "ok\r\nerror:4\r\nerror:6\r\nerror:3\r\nerror:2\r\nerror:10\r\n"
    );
    assert!(p.machine_mut().take_settings_dirty());
    assert_eq!(
        send(&mut p, &mut m, "G0 X1\n"),
        "[MSG:Job started]\r\nok\r\n"
    );
    assert_eq!(moves(&m)[0].target, [100, 0, 0]);
    // Not while moving.
    assert_eq!(send(&mut p, &mut m, "$100=80\n"), "error:8\r\n");
}

#[test]
fn offsets_listing_names_every_slot() {
    let (mut p, mut m) = boot();
    send(
        &mut p,
        &mut m,
        "G10 L2 P1 X5\nG10 L2 P6 Y-2.5\nG28.1\nG0 X1\nG30.1\nG92 X0\n",
    );
    // G30.1 is a sync point: it (and the lines after it) run once G0 X1 has finished.
    m.run_all();
    p.poll(&mut m, 0);
    assert_eq!(drain(&mut p), "ok\r\nok\r\n");
    let out = send(&mut p, &mut m, "$#\n");
    let zero = "0.000,0.000,0.000";
    assert_eq!(
        out,
        format!(
            "[G54:5.000,0.000,0.000]\r\n[G55:{zero}]\r\n[G56:{zero}]\r\n[G57:{zero}]\r\n\
             [G58:{zero}]\r\n[G59:0.000,-2.500,0.000]\r\n[G28:{zero}]\r\n\
             [G30:6.000,0.000,0.000]\r\n[G92:1.000,0.000,0.000]\r\n[TLO:0.000]\r\n\
             [PRB:0.000,0.000,0.000:0]\r\nok\r\n"
        )
    );
}

#[test]
fn info_modal_state_offsets_and_startup_lines() {
    let (mut p, mut m) = boot();
    let out = send(&mut p, &mut m, "$G\n");
    assert_eq!(out, "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
    let out = send(&mut p, &mut m, "$I\n");
    assert!(out.starts_with("[VER:1.1h.inkstep"), "{out}");
    assert!(
        out.contains(
            "[OPT:NL,16,128]\r\n[MSG:Max step rate 80000/s; ellipses, sines, point-by-point arcs 7000/s]\r\n"
        ),
        "{out}"
    );
    // A longer step pulse lowers the cap, and $I says so: 20 us of pulse and 2 of low
    // time, 45,454 events/s.
    assert_eq!(send(&mut p, &mut m, "$0=20\n"), "ok\r\n");
    let out = send(&mut p, &mut m, "$I\n");
    assert!(
        out.contains("[MSG:Max step rate 45454/s; ellipses, sines, point-by-point arcs 7000/s]"),
        "{out}"
    );
    assert_eq!(send(&mut p, &mut m, "$0=10\n"), "ok\r\n");
    send(&mut p, &mut m, "G10 L2 P1 X5\n");
    let out = send(&mut p, &mut m, "$#\n");
    assert!(out.starts_with("[G54:5.000,0.000,0.000]\r\n[G55:"), "{out}");
    assert!(out.ends_with("[TLO:0.000]\r\n[PRB:0.000,0.000,0.000:0]\r\nok\r\n"));
    assert_eq!(
        send(&mut p, &mut m, "$N0=G20 G91\n$N1=G5\n"),
        "ok\r\nerror:20\r\n"
    );
    assert_eq!(send(&mut p, &mut m, "$N\n"), "$N0=G20G91\r\n$N1=\r\nok\r\n");
    let out = send(&mut p, &mut m, "\x18");
    assert_eq!(out, format!("\r\n{WELCOME}\r\n>G20G91:ok\r\n"));
    assert!(send(&mut p, &mut m, "$G\n").contains("G20 G91"));
}

#[test]
fn job_messages_pause_and_overrides() {
    let (mut p, mut m) = boot();
    let out = send(&mut p, &mut m, "G1 X1 F100\nM0\nG1 X2\n");
    assert_eq!(
        out, "[MSG:Job started]\r\nok\r\n",
        "M0 waits for the motion before it"
    );
    m.run_all();
    p.poll(&mut m, 10);
    assert_eq!(
        drain(&mut p),
        "ok\r\nok\r\n",
        "M0 ran, the line after it queued"
    );
    assert!(
        send(&mut p, &mut m, "?").starts_with("<Hold:0|"),
        "M0 holds at rest"
    );
    assert_eq!(moves(&m).len(), 2);
    m.run_all();
    assert_eq!(m.pos[0], 80, "the queued line waits for cycle start");
    assert_eq!(send(&mut p, &mut m, "~"), "");
    assert!(send(&mut p, &mut m, "?").starts_with("<Run|"));
    p.receive(b"M2\n", &mut m, 0);
    p.poll(&mut m, 0);
    assert_eq!(drain(&mut p), "", "M2 waits for the motion before it");
    m.run_all();
    // As the protocol task runs lines: the machine looks again after M2's line, and
    // finds the job done.
    p.poll(&mut m, 1500);
    assert_eq!(
        drain(&mut p),
        "[MSG:Pgm End]\r\nok\r\n[MSG:Job finished: 1.500 s, 2 moves]\r\n"
    );
    send(&mut p, &mut m, "\u{91}\u{91}\u{96}");
    assert_eq!(m.overrides, (120, 50));
    assert!(send(&mut p, &mut m, "?").contains("|Ov:120,50,100"));
    send(&mut p, &mut m, "\u{90}");
    assert_eq!(m.overrides, (100, 50));
}

#[test]
fn long_lines_get_error_11() {
    let (mut p, mut m) = boot();
    let long = format!("G1 X{}\n", "1".repeat(90));
    assert_eq!(send(&mut p, &mut m, &long), "error:11\r\n");
    assert_eq!(
        send(&mut p, &mut m, "G0 X1\n"),
        "[MSG:Job started]\r\nok\r\n"
    );
}

#[test]
fn work_position_reports_pen_speed_and_notifications() {
    let (mut p, mut m) = boot();
    send(
        &mut p,
        &mut m,
        "$10=0\nG10 L2 P1 X2 Y3\nG0 X5 Y5\nM3 S250\n",
    );
    m.run_all();
    let out = send(&mut p, &mut m, "?");
    // M3 S250: a quarter of the way down ($31 = 0, $30 = 1000), and reported down.
    assert!(
        out.starts_with("<Idle|WPos:5.000,5.000,-0.500|FS:0,250|"),
        "{out}"
    );
    assert!(out.ends_with("|A:S>\r\n"), "{out}");
    p.notify("Stored data corrupt, defaults restored");
    assert_eq!(
        drain(&mut p),
        "[MSG:Stored data corrupt, defaults restored]\r\n"
    );
}

#[test]
fn busy_follows_motion() {
    let (mut p, mut m) = boot();
    assert!(!p.machine().busy(&m));
    send(&mut p, &mut m, "G0 X1\n");
    assert!(p.machine().busy(&m));
    m.run_all();
    assert!(!p.machine().busy(&m));
}

#[test]
fn ram_budget_of_the_protocol() {
    use inkstep_core::gcode::Interpreter;
    use inkstep_core::machine::Machine;
    let sizes = (
        std::mem::size_of::<Protocol>(),
        std::mem::size_of::<Machine>(),
        std::mem::size_of::<Interpreter>(),
        std::mem::size_of::<Settings>(),
    );
    println!(
        "RAM: Protocol {} B (Machine {} B, Interpreter {} B, Settings {} B)",
        sizes.0, sizes.1, sizes.2, sizes.3
    );
    // The image's RAM (statics plus the worst-case stack, at most 19 KB) is checked on
    // the image itself by .ci/size-table; this catches a protocol that grows by much
    // sooner, on the host: it takes 2,080 B here (about 1.9 KB on the target).
    assert!(sizes.0 <= 2304, "{sizes:?}");
}

#[test]
fn huge_positions_never_overrun_the_output() {
    let (mut p, mut m) = boot();
    send(
        &mut p,
        &mut m,
        "$100=0.001\n$101=0.001\n$102=0.001\nG10 L2 P1 X-999999999 Y-999999999 Z-999999999\n",
    );
    m.pos = [-1_000_000_000; 3];
    p.set_inputs(
        Inputs {
            limits: [true; 3],
            feed_hold: true,
            cycle_start: true,
            estop: false,
        },
        &mut m,
        0,
    );
    for _ in 0..50 {
        p.receive(b"?", &mut m, 0);
        p.poll(&mut m, 0);
        drain(&mut p);
    }
    assert_eq!(p.truncated(), 0);
}

#[test]
fn keypad_moves_and_abort_keep_the_interpreter_in_step() {
    let (mut p, mut m) = boot();
    m.rate = 8;
    let mv = Move {
        target: [800, 800, 0],
        path: Path::Line,
        feed: Feed::MmPerMin(300.0),
        line: 0,
    };
    p.machine_mut().queue(Command::Move(mv), &mut m, 0).unwrap();
    assert_eq!(drain(&mut p), "");
    p.poll(&mut m, 0);
    assert_eq!(drain(&mut p), "[MSG:Job started]\r\n");
    m.step();
    p.machine_mut().stop_and_clear(&mut m);
    // Cycle start cannot undo an abort, and G-code waits until the stop is done.
    p.receive(b"~", &mut m, 0);
    assert!(m.holding);
    p.receive(b"G4 P0\n", &mut m, 0);
    p.poll(&mut m, 0);
    assert!(drain(&mut p).is_empty(), "the line waits");
    assert_eq!(m.queue.len(), 1);
    m.step();
    p.poll(&mut m, 0);
    assert_eq!(drain(&mut p), "", "G4 runs: its ok waits for the dwell");
    assert_eq!(m.queue.len(), 1, "only the dwell is queued");
    m.step();
    p.poll(&mut m, 0);
    assert_eq!(drain(&mut p), "ok\r\n");
    m.run_all();
    assert_eq!(m.pos, [16, 16, 0], "one step of deceleration");
    assert_eq!(p.machine().state(&m), RunState::Idle);
    // G-code continues from where the abort stopped.
    send(&mut p, &mut m, "G91 G0 X1\n");
    assert_eq!(moves(&m).last().unwrap().target, [96, 16, 0]);
    // Refused in alarm.
    send(&mut p, &mut m, "\x18");
    p.set_inputs(
        Inputs {
            estop: true,
            ..Inputs::default()
        },
        &mut m,
        0,
    );
    let r = p.machine_mut().queue(Command::Move(mv), &mut m, 0);
    assert_eq!(r, Err(inkstep_core::gcode::ErrorCode::SystemLocked));
}

#[test]
fn hundred_thousand_lines_in_usb_packets_lose_and_duplicate_nothing() {
    // Send-response would be too slow to matter here; use character counting with
    // the bytes cut into 64-byte USB packets that the protocol may only partly take.
    let started = std::time::Instant::now();
    let (mut p, mut m) = boot();
    m.cap = 15;
    let n = 100_000;
    let lines: Vec<String> = (0..n)
        .map(|i| i + 1) // line 0 would be X0 Y0: no motion from the origin
        .map(|i| {
            format!(
                "G1 X{:.3} Y{:.3} F3000",
                (i % 997) as f32 * 0.125,
                (i % 89) as f32 * 0.25
            )
        })
        .collect();
    let mut in_flight = std::collections::VecDeque::new();
    let mut wire: Vec<u8> = Vec::new(); // bytes written by the sender, not yet read
    let mut next = 0;
    let mut acks = 0;
    let mut pending = String::new();
    while acks < n {
        while next < n {
            let len = lines[next].len() + 1;
            if in_flight.iter().sum::<usize>() + len > RX_BUFFER_SIZE {
                break;
            }
            wire.extend_from_slice(lines[next].as_bytes());
            wire.push(b'\n');
            in_flight.push_back(len);
            next += 1;
        }
        let packet = wire.len().min(64);
        let taken = p.receive(&wire[..packet], &mut m, 0);
        wire.drain(..taken);
        p.poll(&mut m, 0);
        pending.push_str(&drain(&mut p));
        while let Some(end) = pending.find("\r\n") {
            let resp: String = pending.drain(..end + 2).collect();
            match resp.trim_end() {
                "ok" => {
                    in_flight.pop_front();
                    acks += 1;
                }
                "[MSG:Job started]" => {}
                other => panic!("unexpected {other:?}"),
            }
        }
        m.step();
    }
    m.run_all();
    let mv = moves(&m);
    assert_eq!(mv.len(), n, "one move per line");
    for (i, mv) in mv.iter().enumerate() {
        let i = i + 1;
        let x = ((i % 997) as f32 * 0.125 * 80.0).round() as i32;
        let y = ((i % 89) as f32 * 0.25 * 80.0).round() as i32;
        assert_eq!(mv.target, [x, y, 0], "line {i}");
    }
    let last = n;
    assert_eq!(
        m.pos,
        [((last % 997) * 10) as i32, ((last % 89) * 20) as i32, 0]
    );
    println!("100000 lines streamed in {:?}", started.elapsed());
}

#[test]
fn an_alarm_during_a_jog_cancel_leaves_nothing_pending() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "$J=G91 X10 F500\n");
    p.receive(b"\x85!", &mut m, 0);
    p.set_inputs(
        Inputs {
            estop: true,
            ..Inputs::default()
        },
        &mut m,
        0,
    );
    p.set_inputs(Inputs::default(), &mut m, 0);
    send(&mut p, &mut m, "\x18$X\n");
    assert_eq!(p.machine().state(&m), RunState::Idle);
    assert_eq!(
        send(&mut p, &mut m, "G0 X1\n"),
        "[MSG:Job started]\r\nok\r\n"
    );
}

#[test]
fn changing_steps_per_mm_keeps_the_real_position() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "G0 X10\n");
    m.run_all();
    send(&mut p, &mut m, "$100=100\n");
    assert!(send(&mut p, &mut m, "?").starts_with("<Idle|MPos:8.000,"));
    send(&mut p, &mut m, "G91 G0 X1\n");
    assert_eq!(
        moves(&m).last().unwrap().target,
        [900, 0, 0],
        "1 mm from where it is"
    );
}

#[test]
fn safety_door_holds_reports_door_and_resumes_on_cycle_start() {
    let (mut p, mut m) = boot();
    m.rate = 8;
    send(&mut p, &mut m, "G1 X10 F600\n");
    m.step();
    p.receive(b"\x84?", &mut m, 0);
    assert!(drain(&mut p).starts_with("<Door:2|"), "stopping");
    m.step();
    assert!(send(&mut p, &mut m, "?").starts_with("<Door:0|"));
    m.step();
    assert_eq!(m.pos[0], 16, "no step once at rest");
    send(&mut p, &mut m, "~");
    assert!(send(&mut p, &mut m, "?").starts_with("<Run|"));
    // During homing the door aborts it.
    m.run_all();
    send(&mut p, &mut m, "$22=1\n$H\n");
    let out = send(&mut p, &mut m, "\u{84}");
    assert!(out.starts_with("ALARM:7"), "{out}");
}

#[test]
fn dollar_commands_while_running_are_refused_without_effect() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "G0 X10\n");
    assert_eq!(send(&mut p, &mut m, "$N0=G21\n"), "error:8\r\n");
    assert_eq!(
        send(&mut p, &mut m, "$RST=*\n$$\n$#\n$I\n$X\n$100=10\n"),
        "error:8\r\n".repeat(6)
    );
    assert!(
        send(&mut p, &mut m, "$G\n").ends_with("ok\r\n"),
        "$G works at any time"
    );
    m.run_all();
    assert_eq!(
        send(&mut p, &mut m, "$N\n"),
        "$N0=\r\n$N1=\r\nok\r\n",
        "nothing was stored"
    );
}

#[test]
fn g4_answers_after_the_motion_before_it_and_its_dwell() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "G1 X20 F600\n");
    p.receive(b"G4 P0.5\nG0 Y[posx]\nG0 Y1\n", &mut m, 0);
    p.poll(&mut m, 0);
    assert_eq!(drain(&mut p), "", "G4 waits while the move runs");
    assert_eq!(m.queue.len(), 1, "nothing after G4 is queued either");
    m.step();
    p.poll(&mut m, 0);
    assert_eq!(
        drain(&mut p),
        "",
        "the move ended: the dwell runs, no ok yet"
    );
    assert_eq!(m.queue.front(), Some(&Command::Dwell { ms: 500 }));
    // Grbl reports a dwell as Idle: it is no motion.
    assert!(send(&mut p, &mut m, "?").starts_with("<Idle|MPos:20.000,"));
    m.step();
    p.poll(&mut m, 0);
    assert_eq!(
        drain(&mut p),
        "ok\r\nerror:2\r\nok\r\n",
        "the dwell ended: ok, then the lines after it"
    );
}

#[test]
fn sync_points_wait_for_the_motion_before_them() {
    // Grbl's documented sync points: dwell, program pause and end, and every command
    // that writes stored data or changes the work coordinate offset.
    let sync = [
        "G4 P0",
        "M0",
        "M2",
        "M30",
        "G10 L2 P1 X1",
        "G10 L20 P0 X0",
        "G28.1",
        "G30.1",
        "G92 X0",
        "G92.1",
        "G55",
    ];
    for line in sync {
        let (mut p, mut m) = boot();
        send(&mut p, &mut m, "G1 X1 F100\n");
        p.receive(format!("{line}\n").as_bytes(), &mut m, 0);
        p.poll(&mut m, 0);
        assert_eq!(drain(&mut p), "", "{line} waits for the move");
        m.run_all();
        p.poll(&mut m, 0);
        m.step(); // a dwell
        p.poll(&mut m, 0);
        assert!(drain(&mut p).contains("ok\r\n"), "{line} runs after it");
    }
    // Queued like moves: G28/G30 (they move), the pen (M3/M5, the one deliberate
    // difference: it is a motion in the queue), modes that change no offset.
    let queued = [
        "G28", "G30", "M3", "M5", "G54", "G20", "G91", "G17", "M8", "S100",
    ];
    for line in queued {
        let (mut p, mut m) = boot();
        send(&mut p, &mut m, "G1 X1 F100\n");
        assert_eq!(
            send(&mut p, &mut m, &format!("{line}\n")),
            "ok\r\n",
            "{line} is answered at once"
        );
    }
}

#[test]
fn dynamic_tool_length_offset_g43_1_and_g49() {
    let (mut p, mut m) = boot();
    assert_eq!(send(&mut p, &mut m, "G43.1 Z2\n"), "ok\r\n");
    let gc = send(&mut p, &mut m, "$G\n");
    assert_eq!(
        gc,
        "[GC:G0 G54 G17 G21 G90 G94 G43.1 M5 M9 T0 F0 S0]\r\nok\r\n"
    );
    let params = send(&mut p, &mut m, "$#\n");
    assert!(params.contains("[TLO:2.000]\r\n"), "{params}");
    assert!(send(&mut p, &mut m, "?").contains("|WCO:0.000,0.000,2.000"));
    // Z in work coordinates moves past the offset: Z0 is machine Z 2 (400 steps/mm).
    send(&mut p, &mut m, "G1 Z0 F100\n");
    assert_eq!(moves(&m).last().unwrap().target, [0, 0, 800]);
    m.run_all();
    // G92 and G10 L20 account for it: the current Z reads as the word.
    send(&mut p, &mut m, "G92 Z1\n");
    assert!(send(&mut p, &mut m, "?").contains("|WCO:0.000,0.000,1.000"));
    send(&mut p, &mut m, "G92.1\nG10 L20 P1 Z0\n");
    assert!(send(&mut p, &mut m, "?").contains("|WCO:0.000,0.000,2.000"));
    send(&mut p, &mut m, "G10 L2 P1 Z0\n");
    // Only Z, and not beside motion or another axis command (Grbl's errors 37, 24).
    assert_eq!(
        send(&mut p, &mut m, "G43.1 X1\nG1 G43.1 Z1\nG92 G43.1 Z1\n"),
        "error:37\r\nerror:24\r\nerror:24\r\n"
    );
    // A bare G43.1 keeps the offset (bCNC replays the $G words, then sends G43.1 Z).
    assert_eq!(
        send(
            &mut p,
            &mut m,
            "G0 G54 G17 G21 G90 G94 G43.1\nG43.1Z0.000\n"
        ),
        "ok\r\nok\r\n"
    );
    assert!(send(&mut p, &mut m, "$#\n").contains("[TLO:0.000]"));
    send(&mut p, &mut m, "G43.1 Z3\n");
    assert_eq!(send(&mut p, &mut m, "G49\n"), "ok\r\n");
    assert!(send(&mut p, &mut m, "$#\n").contains("[TLO:0.000]"));
    assert!(!send(&mut p, &mut m, "$G\n").contains("G43.1"));
    // A soft reset clears it, as Grbl's non-persistent offsets.
    send(&mut p, &mut m, "G43.1 Z3\n\x18");
    assert!(send(&mut p, &mut m, "$#\n").contains("[TLO:0.000]"));
    assert!(!send(&mut p, &mut m, "$G\n").contains("G43.1"));
}

#[test]
fn a_start_or_reset_in_alarm_says_how_to_unlock() {
    let mut settings = Settings::default();
    settings.set(22, 1.0).unwrap(); // homing enabled: starts locked until $H or $X
    let mut p = Protocol::new(settings);
    let mut m = FakePlanner::new(16);
    let unlock = format!("\r\n{WELCOME}\r\n[MSG:'$H'|'$X' to unlock]\r\n");
    assert_eq!(drain(&mut p), unlock, "at power-up");
    assert_eq!(send(&mut p, &mut m, "\x18"), unlock, "after a reset");
    assert!(send(&mut p, &mut m, "$X\n").ends_with("ok\r\n"));
    // Unlocked but not homed: a reset locks it again, and says so.
    assert_eq!(send(&mut p, &mut m, "\x18"), unlock);
}

#[test]
fn every_query_gets_its_own_report_even_while_the_output_is_busy() {
    let (mut p, mut m) = boot();
    // A `$$` listing fills the output buffer as fast as it drains; three `?` arrive
    // together meanwhile (a sender whose reads were held up).
    p.receive(b"$$\n", &mut m, 0);
    p.poll(&mut m, 0);
    assert_eq!(p.receive(b"???", &mut m, 0), 3);
    let mut out = String::new();
    for _ in 0..200 {
        p.poll(&mut m, 0);
        out.push_str(&drain(&mut p));
    }
    assert_eq!(out.matches("<Idle|").count(), 3, "{out}");
    assert!(out.ends_with("ok\r\n") || out.contains("$215="), "{out}");
}

#[test]
fn a_line_refused_for_planner_room_is_interpreted_once() {
    use inkstep_core::machine::{Machine, Taken};
    let mut machine = Machine::new(Settings::default());
    let mut m = FakePlanner::new(1);
    assert_eq!(
        machine.execute(b"G1X1F1000", 1, &mut m, 0),
        Some(Ok(Taken::Now))
    );
    // The planner is full: the relative move is interpreted (G91 is in force at once,
    // as for any line already taken) and its move waits, however often it is retried.
    for _ in 0..5 {
        assert_eq!(machine.execute(b"G91G1X2", 2, &mut m, 0), None);
    }
    assert!(machine.interpreter().modal().incremental);
    m.run_all();
    // The retry that finds room pushes the kept move without reading the line again
    // (a caller always passes the same line; this one is not even G-code).
    assert_eq!(
        machine.execute(b"not read", 2, &mut m, 0),
        Some(Ok(Taken::Now))
    );
    m.run_all();
    // G91 and X2 applied once: the next relative move starts at X3.
    assert_eq!(machine.execute(b"X1", 3, &mut m, 0), Some(Ok(Taken::Now)));
    let xs: Vec<i32> = moves(&m).iter().map(|mv| mv.target[0]).collect();
    assert_eq!(xs, [80, 240, 320]);
}

#[test]
fn a_waiting_line_is_dropped_by_a_soft_reset_and_refused_in_alarm() {
    // The second line waits for room behind the first.
    let queue_two = |p: &mut Protocol, m: &mut FakePlanner| {
        m.cap = 1;
        p.receive(b"G1 X1 F1000\nG1 X5\n", m, 0);
        p.poll(m, 0);
        assert!(drain(p).ends_with("]\r\nok\r\n"));
    };
    // A soft reset drops it (unanswered, as every buffered line).
    let (mut p, mut m) = boot();
    queue_two(&mut p, &mut m);
    p.receive(&[0x18], &mut m, 0);
    m.run_all();
    p.poll(&mut m, 0);
    let out = drain(&mut p);
    assert!(!out.contains("ok"), "{out}");
    assert_eq!(
        moves(&m).len(),
        1,
        "the waiting move never reaches the planner"
    );
    // An alarm while it waits: it is answered error:9 and never pushed.
    let (mut p, mut m) = boot();
    queue_two(&mut p, &mut m);
    let estop = Inputs {
        estop: true,
        ..Inputs::default()
    };
    p.set_inputs(estop, &mut m, 0);
    p.poll(&mut m, 0);
    let out = drain(&mut p);
    assert!(out.contains("error:9"), "{out}");
    assert_eq!(moves(&m).len(), 1);
}

#[test]
fn feed_hold_at_idle_holds_the_next_move_until_cycle_start() {
    let (mut p, mut m) = boot();
    send(&mut p, &mut m, "!");
    assert!(send(&mut p, &mut m, "?").starts_with("<Hold:0|"), "as Grbl");
    assert!(send(&mut p, &mut m, "G1 X10 F600\n").ends_with("ok\r\n"));
    for _ in 0..10 {
        m.step();
    }
    assert_eq!(m.pos, [0, 0, 0], "the move waits for ~");
    assert!(send(&mut p, &mut m, "?").starts_with("<Hold:0|"));
    send(&mut p, &mut m, "~");
    m.run_all();
    assert_eq!(m.pos, [800, 0, 0]);
    assert!(send(&mut p, &mut m, "?").starts_with("<Idle|MPos:10.000,"));
}

#[test]
fn three_hundred_resets_in_one_write_then_a_query_cut_no_line() {
    let (mut p, mut m) = boot();
    let mut bytes = vec![0x18u8; 300];
    bytes.push(b'?');
    let out = send(&mut p, &mut m, std::str::from_utf8(&bytes).unwrap());
    assert_eq!(p.truncated(), 0);
    for line in out.split("\r\n").filter(|l| !l.is_empty()) {
        assert!(
            line == WELCOME || (line.starts_with("<Idle|") && line.ends_with('>')),
            "cut or unexpected line {line:?} in {out:?}"
        );
    }
    assert!(out.ends_with(">\r\n"), "the ? is answered last: {out:?}");
    assert_eq!(out.matches('<').count(), 1);
}

#[test]
fn five_hundred_queries_in_one_write_get_five_hundred_reports() {
    let (mut p, mut m) = boot();
    let out = send(&mut p, &mut m, &"?".repeat(500));
    assert_eq!(p.truncated(), 0);
    let reports: Vec<&str> = out.split("\r\n").filter(|l| !l.is_empty()).collect();
    assert_eq!(reports.len(), 500);
    assert!(reports
        .iter()
        .all(|r| r.starts_with("<Idle|") && r.ends_with('>')));
}

#[test]
fn sleep_releases_the_motors_refuses_everything_and_wakes_in_alarm_on_reset() {
    let (mut p, mut m) = boot();
    assert!(!p.machine().motors_released());
    assert_eq!(send(&mut p, &mut m, "$SLP\n"), "ok\r\n");
    assert!(p.machine().motors_released());
    assert!(send(&mut p, &mut m, "?").starts_with("<Sleep|"));
    assert_eq!(send(&mut p, &mut m, "G0 X1\n"), "error:9\r\n");
    assert_eq!(send(&mut p, &mut m, "$X\n"), "error:8\r\n");
    assert_eq!(send(&mut p, &mut m, "$J=G91 X1 F100\n"), "error:8\r\n");
    assert!(moves(&m).is_empty());
    let out = send(&mut p, &mut m, "\x18");
    assert_eq!(
        out,
        format!("\r\n{WELCOME}\r\n[MSG:'$H'|'$X' to unlock]\r\n"),
        "awake in alarm: the motors were unpowered"
    );
    assert!(!p.machine().motors_released());
    assert_eq!(
        send(&mut p, &mut m, "$X\n"),
        "[MSG:Caution: Unlocked]\r\nok\r\n"
    );
    assert!(send(&mut p, &mut m, "G0 X1\n").ends_with("ok\r\n"));
}

#[test]
fn spindle_settings_hold_the_reported_s() {
    let (mut p, mut m) = boot();
    assert_eq!(
        send(&mut p, &mut m, "$30=500\n$31=100\n$32=1\n"),
        "ok\r\nok\r\nok\r\n"
    );
    send(&mut p, &mut m, "M3 S2000\nG1 X10 F600\n");
    let out = send(&mut p, &mut m, "?");
    assert!(out.contains("|FS:600,500"), "S held to $30: {out}");
    m.run_all();
    let out = send(&mut p, &mut m, "$$\n");
    assert!(
        out.contains("$27=1.000\r\n$30=500.000\r\n$31=100.000\r\n$32=1\r\n$100="),
        "listed by number: {out}"
    );
}

/// `(MSG, text)` answers `[MSG:text]` before the line's `ok` ("MSG" in any case,
/// spaces around the comma, on a line of its own or beside G-code); other comments
/// say nothing. While the machine waits for the user (M0), a new message waits too,
/// so the prompt keeps the message it was given.
#[test]
fn msg_comments_are_passed_on_and_wait_while_the_machine_waits() {
    let (mut p, mut m) = boot();
    assert_eq!(
        send(&mut p, &mut m, "(MSG,pen 2: red)\n"),
        "[MSG:pen 2: red]\r\nok\r\n"
    );
    assert_eq!(
        send(&mut p, &mut m, "( msg , Change paper )\n"),
        "[MSG:Change paper ]\r\nok\r\n"
    );
    assert_eq!(
        send(&mut p, &mut m, "(message)\n(MSG no comma)\n"),
        "ok\r\nok\r\n"
    );
    assert_eq!(p.machine().message(), b"Change paper ");
    let out = send(&mut p, &mut m, "G0 X1 (MSG,moving)\n");
    assert!(out.starts_with("[MSG:moving]\r\n"), "{out}");
    m.run_all();
    let out = send(&mut p, &mut m, "M0\n(MSG,after)\n");
    assert!(out.starts_with("ok\r\n"), "{out}");
    assert!(!out.contains("after"), "waits while paused: {out}");
    assert_eq!(p.machine().message(), b"moving");
    let out = send(&mut p, &mut m, "~");
    assert!(out.contains("[MSG:after]\r\nok\r\n"), "{out}");
}
