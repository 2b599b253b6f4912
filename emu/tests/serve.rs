//! `cargo emu serve` as a sender meets it: the board's USB port on a pty, opened and
//! closed by a program on the PC (DTR follows). The welcome line when a sender opens
//! the port after power-up (issue 13, point 5), and a sender that crashes mid-job
//! (point 4): the board keeps its position and answers `?` when the port is opened
//! again. Real time: the emulator runs at 1x here.

mod common;

use inkstep_serial::grbl::{parse_reply, Reply};
use inkstep_serial::port::{Port, Transport};
use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

/// `cargo emu serve` on a link in a temporary folder; killed when dropped.
struct Serve {
    child: Child,
    link: PathBuf,
    _dir: tempfile::TempDir,
}

impl Serve {
    fn start() -> Serve {
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("tty");
        let child = Command::new(env!("CARGO_BIN_EXE_inkstep-emu"))
            .args(["serve", "--speed", "1", "--log"])
            .arg(dir.path().join("log.txt"))
            .arg("--elf")
            .arg(common::elf())
            .arg("--link")
            .arg(&link)
            .spawn()
            .unwrap();
        let t = Instant::now();
        while !link.exists() {
            assert!(t.elapsed() < Duration::from_secs(10), "no pty link");
            std::thread::sleep(Duration::from_millis(10));
        }
        Serve {
            child,
            link,
            _dir: dir,
        }
    }

    fn open(&self) -> Port {
        Port::open(path_str(&self.link), 115_200).unwrap()
    }
}

impl Drop for Serve {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Read lines for up to `within`, until `stop` accepts one; returns every line read.
fn read_until(port: &mut Port, within: Duration, stop: impl Fn(&str) -> bool) -> Vec<String> {
    let t = Instant::now();
    let mut text = String::new();
    let mut buf = [0u8; 256];
    while t.elapsed() < within {
        let n = port.recv(&mut buf).unwrap_or(0);
        text.push_str(&String::from_utf8_lossy(&buf[..n]));
        if text.lines().any(&stop) {
            break;
        }
    }
    text.lines().map(|l| l.trim().to_string()).collect()
}

/// A sender that opens the port some time after power-up sees Grbl's welcome line
/// without sending anything (as from a Grbl on an Arduino, which resets on open).
#[test]
fn a_sender_opening_the_port_after_power_up_sees_the_welcome_line() {
    let serve = Serve::start();
    // Power-up, enumeration (~0.15 s) and well after, with the port closed.
    std::thread::sleep(Duration::from_millis(1500));
    let mut port = serve.open();
    let lines = read_until(&mut port, Duration::from_secs(3), |l| {
        matches!(parse_reply(l.trim()), Reply::Welcome(_))
    });
    assert!(
        lines.iter().any(|l| l == "Grbl 1.1h ['$' for help]"),
        "no welcome line on open: {lines:?}"
    );
}

/// The sender dies mid-job (its port closed while the machine draws), another opens
/// the port: the board answers `?`, was not reset, and ends where the job ends.
#[test]
fn a_sender_crash_mid_job_keeps_the_position_and_the_board_answers() {
    let serve = Serve::start();
    std::thread::sleep(Duration::from_millis(500));
    let mut port = serve.open();
    // 60 mm and back 20: about 3 s at 1500 mm/min; all of it fits the receive buffer.
    let job = ["G21 G90", "G1 X60 Y10 F1500", "G1 X40 Y20"];
    for l in job {
        port.send(format!("{l}\n").as_bytes()).unwrap();
    }
    let mut oks = 0;
    let t = Instant::now();
    while oks < job.len() {
        assert!(t.elapsed() < Duration::from_secs(5), "answers: {oks}");
        let lines = read_until(&mut port, Duration::from_millis(200), |l| l == "ok");
        oks += lines.iter().filter(|l| *l == "ok").count();
    }
    std::thread::sleep(Duration::from_millis(500));
    // The crash: the port closes without a word.
    drop(port);
    std::thread::sleep(Duration::from_millis(700));
    let mut port = serve.open();
    let mut states = Vec::new();
    let t = Instant::now();
    let last = loop {
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "no Idle after the reopen: {states:?}"
        );
        port.send(b"?").unwrap();
        let lines = read_until(&mut port, Duration::from_millis(200), |l| {
            l.starts_with('<')
        });
        let mut idle = None;
        for l in &lines {
            if let Reply::Status(st) = parse_reply(l) {
                states.push(st.state.clone());
                if st.state == "Idle" {
                    idle = Some(st);
                }
            }
        }
        if let Some(st) = idle {
            break st;
        }
    };
    assert!(
        states.iter().any(|s| s == "Run"),
        "the job was over before the port came back: {states:?}"
    );
    assert!(!states.iter().any(|s| s == "Alarm"), "{states:?}");
    let pos = last.pos.unwrap();
    assert!(
        (pos[0] - 40.0).abs() < 1e-3 && (pos[1] - 20.0).abs() < 1e-3,
        "the board ended at {pos:?}, not at the job's end (40, 20)"
    );
}
