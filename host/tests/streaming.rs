//! The streamer against the in-process fake Grbl (tests/common), which
//! records any overflow of the 128-byte receive buffer.

mod common;

use common::FakeGrbl;
use inkstep_serial::grbl::Status;
use inkstep_serial::stream::{prepare, stream, Config, Line, Observer, Outcome};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

#[derive(Default)]
struct Log {
    progress: Vec<(usize, usize)>,
    states: Vec<String>,
    messages: Vec<String>,
}

impl Observer for Log {
    fn progress(&mut self, acked: usize, total: usize) {
        self.progress.push((acked, total));
    }
    fn status(&mut self, s: &Status) {
        self.states.push(s.state.clone());
    }
    fn message(&mut self, text: &str) {
        self.messages.push(text.to_string());
    }
}

fn cfg() -> Config {
    Config {
        status_interval: Duration::from_millis(1),
        hold_timeout: Duration::from_secs(2),
        ..Config::default()
    }
}

/// A program with comments, blank lines and lines of varied length.
fn program(n: usize) -> String {
    let mut s = String::from("(header comment)\nG21 G90\n\n");
    for i in 0..n {
        let pad = "0".repeat(i % 37);
        s.push_str(&format!(
            "G1 X{i}.{pad}1 Y{} F1500 ; move {i}\n",
            i * 7 % 101
        ));
    }
    s
}

#[test]
fn every_line_is_acknowledged_and_the_buffer_never_overflows() {
    let prog = program(400);
    let lines = prepare(&prog, 128).unwrap();
    assert_eq!(lines.len(), 401);
    let mut g = FakeGrbl::new();
    let mut log = Log::default();
    let out = stream(&mut g, &lines, &cfg(), &AtomicBool::new(false), &mut log).unwrap();
    assert_eq!(out, Outcome::Done { lines: 401 });
    assert!(
        !g.overflow,
        "more than 128 bytes were in the receive buffer"
    );
    // Character counting really fills the buffer (send-response would not).
    assert!(g.max_fill > 100, "max fill {}", g.max_fill);
    let sent: Vec<&str> = lines.iter().map(|l| l.text.as_str()).collect();
    assert_eq!(g.received, sent);
    assert_eq!(log.progress.last(), Some(&(401, 401)));
    // Done only after the machine reported Idle following the last ok.
    assert_eq!(log.states.last().map(String::as_str), Some("Idle"));
    assert_eq!(g.motion, 0);
}

#[test]
fn an_error_stops_the_stream_naming_the_file_line() {
    let mut prog = program(200);
    prog = prog.replacen("G1 X60.", "G999 X60.", 1);
    let lines = prepare(&prog, 128).unwrap();
    let bad = lines
        .iter()
        .find(|l| l.text.contains("G999"))
        .unwrap()
        .file_line;
    assert_eq!(bad, 3 + 60 + 1);
    let mut g = FakeGrbl::new();
    let mut log = Log::default();
    let out = stream(&mut g, &lines, &cfg(), &AtomicBool::new(false), &mut log).unwrap();
    match out {
        Outcome::Error {
            file_line,
            code,
            text,
        } => {
            assert_eq!((file_line, code), (bad, 20));
            assert!(text.starts_with("G999"));
        }
        o => panic!("{o:?}"),
    }
    assert!(!g.overflow);
    // Feed hold, then soft reset, in that order; nothing executed after it.
    let hold = g.realtime.iter().position(|&b| b == b'!').unwrap();
    let reset = g.realtime.iter().position(|&b| b == 0x18).unwrap();
    assert!(hold < reset);
    assert!(g.received.len() <= 62);
    assert!(log.messages.iter().any(|m| m.starts_with("Grbl 1.1h")));
}

#[test]
fn an_alarm_stops_the_stream() {
    let prog = program(100).replacen("G1 X20.", "G1 LIMIT X20.", 1);
    let lines = prepare(&prog, 128).unwrap();
    let mut g = FakeGrbl::new();
    let out = stream(
        &mut g,
        &lines,
        &cfg(),
        &AtomicBool::new(false),
        &mut Log::default(),
    )
    .unwrap();
    match out {
        // The oldest unanswered line: here the one that raised the alarm.
        Outcome::Alarm {
            code: 1,
            file_line: Some(l),
        } => assert_eq!(l, 3 + 20 + 1),
        o => panic!("{o:?}"),
    }
    assert!(!g.overflow);
}

#[test]
fn stop_flag_holds_then_resets() {
    let prog = program(300);
    let lines = prepare(&prog, 128).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let mut g = FakeGrbl::new();
    g.stop_after = Some((50, stop.clone()));
    let out = stream(&mut g, &lines, &cfg(), &stop, &mut Log::default()).unwrap();
    assert!(
        matches!(out, Outcome::Interrupted { file_line: Some(_) }),
        "{out:?}"
    );
    let hold = g.realtime.iter().position(|&b| b == b'!').unwrap();
    let reset = g.realtime.iter().position(|&b| b == 0x18).unwrap();
    assert!(hold < reset);
    assert!(g.received.len() < 60);
    assert!(!g.overflow);
}

#[test]
fn a_machine_in_alarm_is_not_streamed_to() {
    let lines = prepare("G0 X1\n", 128).unwrap();
    let mut g = FakeGrbl::new();
    g.state = "Alarm".into();
    let out = stream(
        &mut g,
        &lines,
        &cfg(),
        &AtomicBool::new(false),
        &mut Log::default(),
    )
    .unwrap();
    assert_eq!(
        out,
        Outcome::Locked {
            state: "Alarm".into()
        }
    );
    assert!(g.received.is_empty() && g.rx.is_empty());
}

#[test]
fn prepare_cleans_as_grbl_does_and_rejects_oversized_lines() {
    let lines = prepare("G0 X1 (c)\n; only comment\n\n  g1 y2\n", 128).unwrap();
    assert_eq!(
        lines,
        vec![
            Line {
                file_line: 1,
                text: "G0X1".into()
            },
            Line {
                file_line: 4,
                text: "G1Y2".into()
            }
        ]
    );
    let long = format!("G1 X{}\n", "1".repeat(130));
    assert!(prepare(&long, 128).unwrap_err().contains("line 1"));
}

#[test]
fn a_larger_advertised_buffer_is_used_and_respected() {
    let lines = prepare(&program(300), 128).unwrap();
    let mut g = FakeGrbl::new();
    g.rx_cap = 256;
    let mut log = Log::default();
    let out = stream(&mut g, &lines, &cfg(), &AtomicBool::new(false), &mut log).unwrap();
    assert_eq!(out, Outcome::Done { lines: 301 });
    assert!(!g.overflow);
    assert!(g.max_fill > 200, "{}", g.max_fill);
    assert!(log.messages.iter().any(|m| m.contains("256 bytes")));
}

#[test]
fn a_broken_link_is_reported_with_the_line() {
    let lines = prepare(&program(300), 128).unwrap();
    let mut g = FakeGrbl::new();
    g.break_after = Some(40);
    let out = stream(
        &mut g,
        &lines,
        &cfg(),
        &AtomicBool::new(false),
        &mut Log::default(),
    )
    .unwrap();
    match out {
        Outcome::Disconnected {
            file_line: Some(l),
            error,
        } => {
            assert_eq!(l, lines[40].file_line);
            assert!(error.contains("link broken"));
        }
        o => panic!("{o:?}"),
    }
}
