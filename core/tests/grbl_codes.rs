//! Every `error:N` a sender can meet, held against the number Grbl 1.1h documents for
//! the same situation (its wiki's error-code table and the descriptions of the
//! commands). Each row is a situation a sender produces, the line, and Grbl's answer;
//! the rows where inkstep deliberately answers otherwise are listed apart, each with
//! its reason (docs/grbl.md lists them for users).

mod common;

use common::{drain, send, FakePlanner};
use inkstep_core::protocol::Protocol;
use inkstep_core::settings::Settings;

/// The state a line is sent in.
#[derive(Clone, Copy, Debug)]
enum Setup {
    /// Idle after power-up, default settings.
    Idle,
    /// A move is running.
    Running,
    /// A jog is running.
    Jogging,
    /// Homing enabled: locked in alarm after power-up.
    Alarm,
    /// Soft limits on, homed (so that a jog can exceed the travel).
    SoftLimits,
}

fn boot(setup: Setup) -> (Protocol, FakePlanner) {
    let mut s = Settings::default();
    if matches!(setup, Setup::Alarm | Setup::SoftLimits) {
        s.set(22, 1.0).unwrap();
    }
    let mut p = Protocol::new(s);
    let mut m = FakePlanner::new(16);
    drain(&mut p);
    match setup {
        Setup::Idle | Setup::Alarm => {}
        Setup::Running => {
            assert!(send(&mut p, &mut m, "G1 X10 F100\n").ends_with("ok\r\n"));
        }
        Setup::Jogging => {
            assert_eq!(send(&mut p, &mut m, "$J=G91 X10 F100\n"), "ok\r\n");
        }
        Setup::SoftLimits => {
            assert!(send(&mut p, &mut m, "$X\n$20=1\n").ends_with("ok\r\nok\r\n"));
        }
    }
    (p, m)
}

/// The one answer (`ok` or `error:N`) the line got.
fn answer(setup: Setup, line: &str) -> String {
    let (mut p, mut m) = boot(setup);
    let out = send(&mut p, &mut m, &format!("{line}\n"));
    let answers: Vec<&str> = out
        .lines()
        .filter(|l| *l == "ok" || l.starts_with("error:"))
        .collect();
    assert_eq!(answers.len(), 1, "{setup:?} {line:?}: {out:?}");
    answers[0].to_string()
}

/// (state, line, Grbl 1.1h's documented answer).
const GRBL: &[(Setup, &str, &str)] = &[
    // 1: a G-code word must start with a letter.
    (Setup::Idle, "1", "error:1"),
    (Setup::Idle, "G1\u{7f}X1F100", "error:1"),
    (Setup::Idle, "G1 X1.2.3 F100", "error:1"),
    // 2: a word's value missing or malformed; an unknown `$` command.
    (Setup::Idle, "G1 X", "error:2"),
    (Setup::Idle, "$=5", "error:2"),
    (Setup::Idle, "$Z", "error:2"),
    (Setup::Idle, "$100=", "error:2"),
    (Setup::Idle, "$100=abc", "error:2"),
    // 3: a `$` statement not understood (trailing text, no `=`, no such setting).
    (Setup::Idle, "$100=1.2.3", "error:3"),
    (Setup::Idle, "$110=1e30", "error:3"),
    (Setup::Idle, "$100", "error:3"),
    (Setup::Idle, "$99=1", "error:3"),
    (Setup::Idle, "$300=1", "error:3"),
    (Setup::Idle, "$GX", "error:3"),
    (Setup::Idle, "$J", "error:3"),
    (Setup::Idle, "$RST=x", "error:3"),
    (Setup::Idle, "$SLPX", "error:3"),
    // 4: a negative value for a positive quantity.
    (Setup::Idle, "$100=-1", "error:4"),
    (Setup::Idle, "G4 P-1", "error:4"),
    (Setup::Idle, "G1 X1 F-100", "error:4"),
    // 5: homing while it is disabled.
    (Setup::Idle, "$H", "error:5"),
    // 6: step pulse below 3 us.
    (Setup::Idle, "$0=2", "error:6"),
    // 8: a `$` command that needs the machine at rest, or a jog outside Idle/Jog.
    (Setup::Running, "$$", "error:8"),
    (Setup::Running, "$100=80", "error:8"),
    (Setup::Running, "$J=G91 X1 F100", "error:8"),
    (Setup::Alarm, "$J=G91 X1 F100", "error:8"),
    // 9: G-code locked out in alarm and while jogging.
    (Setup::Alarm, "G0 X1", "error:9"),
    (Setup::Jogging, "G0 X1", "error:9"),
    // 10: soft limits need homing.
    (Setup::Idle, "$20=1", "error:10"),
    // 11: a line longer than the line buffer.
    (
        Setup::Idle,
        "G0X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1X1Y1",
        "error:11",
    ),
    // 12: a rate or resolution that asks for more steps per second than the board makes.
    (Setup::Idle, "$110=99999999", "error:12"),
    (Setup::Idle, "$100=5000", "error:12"),
    // 15: a jog beyond the travel (soft limits on).
    (Setup::SoftLimits, "$J=G53 X-500 F100", "error:15"),
    // 16: a jog with a word jogging does not take (G-codes other than G20/21, G90/91,
    // G53; M-codes).
    (Setup::Idle, "$J=G1 X1 F100", "error:16"),
    (Setup::Idle, "$J=X1 F100 M3", "error:16"),
    // 20: an unsupported command or letter.
    (Setup::Idle, "G5 X1", "error:20"),
    (Setup::Idle, "G-1", "error:20"),
    (Setup::Idle, "M62", "error:20"),
    (Setup::Idle, "Q1", "error:20"),
    (Setup::Idle, "G10 L3 P1 X1", "error:20"),
    // 21: two commands of one modal group.
    (Setup::Idle, "G0 G1 X1", "error:21"),
    // 22: a feed motion without a feed rate.
    (Setup::Idle, "G1 X1", "error:22"),
    (Setup::Idle, "$J=X1", "error:22"),
    (Setup::Idle, "G93 G1 X1", "error:22"),
    // 23: a command that needs a whole number.
    (Setup::Idle, "G1.5 X1", "error:23"),
    (Setup::Idle, "G59.1", "error:23"),
    (Setup::Idle, "G10 L2.5 P1 X1", "error:23"),
    // 24: two commands that both take the axis words.
    (Setup::Idle, "G0 G92 X1", "error:24"),
    // 25: a word repeated.
    (Setup::Idle, "G0 X1 X2", "error:25"),
    // 26: a command that needs axis words without them.
    (Setup::Idle, "G10 L2 P1", "error:26"),
    // 27: a line number above 10,000,000.
    (Setup::Idle, "N10000001 G0 X1", "error:27"),
    // 28: a command without its value word.
    (Setup::Idle, "G4", "error:28"),
    (Setup::Idle, "G10 P1 X1", "error:28"),
    // 29: a coordinate system above G59.
    (Setup::Idle, "G10 L2 P7 X1", "error:29"),
    // 30: G53 with a motion other than G0/G1.
    (Setup::Idle, "G53 G2 X1 I1 F10", "error:30"),
    // 31: axis words no command uses.
    (Setup::Idle, "G80 X1", "error:31"),
    // 32: an arc without an axis word in its plane.
    (Setup::Idle, "G2 Z1 I1 F10", "error:32"),
    // 33: an arc whose target is not a valid end point.
    (Setup::Idle, "G2 X0 R2 F10", "error:33"),
    (Setup::Idle, "G2 X10 I1 F10", "error:33"),
    // 34: an arc radius too small for its chord.
    (Setup::Idle, "G2 X10 R2 F10", "error:34"),
    // 35: an I/J arc without an offset in its plane.
    (Setup::Idle, "G2 X1 F10", "error:35"),
    // 36: value words nothing uses (in a jog too).
    (Setup::Idle, "G0 X1 I2", "error:36"),
    (Setup::Idle, "$J=X1F100S5", "error:36"),
    // 37: G43.1 on another axis than Z.
    (Setup::Idle, "G43.1 X1", "error:37"),
    // 38: a tool number above 255.
    (Setup::Idle, "T300", "error:38"),
    // Accepted by Grbl, and so here.
    (Setup::Idle, "N10000000 G0 X1", "ok"),
    (Setup::Idle, "$10=255", "ok"),
    (Setup::Idle, "$SLP", "ok"),
    (Setup::Idle, "$30=1000", "ok"),
    (Setup::Idle, "$31=0", "ok"),
    (Setup::Idle, "$32=1", "ok"),
    (Setup::Idle, "$J=N5 G91 X1 F100", "ok"),
];

/// Where inkstep answers otherwise on purpose: (state, line, Grbl's answer, inkstep's,
/// why). docs/grbl.md lists the same.
const DIFFERENT: &[(Setup, &str, &str, &str, &str)] = &[
    (
        Setup::Idle,
        "$100=0",
        "ok",
        "error:3",
        "a resolution of 0 steps/mm divides by zero in every conversion to steps: below 0.001 is refused",
    ),
    (
        Setup::Idle,
        "G93 G0 X1",
        "error:22",
        "ok",
        "a rapid ignores the feed rate (RS274/NGC); Grbl's check names G0 by a slip in its condition",
    ),
    (
        Setup::Idle,
        "M6",
        "error:20",
        "ok",
        "a manual pen change: the pen lifts, the machine holds with a [MSG:] until cycle start",
    ),
];

#[test]
fn every_error_code_is_grbls() {
    let mut wrong = Vec::new();
    for &(setup, line, grbl) in GRBL {
        let got = answer(setup, line);
        if got != grbl {
            wrong.push(format!("{setup:?} {line:?}: Grbl {grbl}, inkstep {got}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "{} differ:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

#[test]
fn the_deliberate_differences_are_as_documented() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/grbl.md")).unwrap();
    for &(setup, line, grbl, ours, why) in DIFFERENT {
        assert_ne!(grbl, ours);
        assert_eq!(answer(setup, line), ours, "{line}: {why}");
        assert!(
            doc.contains(&format!("`{line}`")),
            "docs/grbl.md must list `{line}`"
        );
    }
}

/// Every number of Grbl's documented error table that a plotter can meet has a row
/// above (7: a settings read failure shows as a message at boot; 13: the door has no
/// switch; 14: a startup line cannot exceed the line buffer here; 17: no laser PWM).
#[test]
fn the_table_covers_every_code() {
    let mut seen: Vec<u8> = GRBL
        .iter()
        .filter_map(|(_, _, a)| a.strip_prefix("error:"))
        .map(|n| n.parse().unwrap())
        .collect();
    seen.sort();
    seen.dedup();
    let all: Vec<u8> = (1..=38)
        .filter(|n| ![7, 13, 14, 17, 18, 19].contains(n))
        .collect();
    assert_eq!(seen, all);
}
