//! `cargo sim serve` end to end: the binary opens a pty, a client sends `?` and G-code
//! and reads the status report and `ok`s, as a Grbl sender would.

use std::io::{Read, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

struct Killed(Child);
impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Reads from the non-blocking port until `done` holds or 5 s pass.
fn read_while(port: &mut std::fs::File, got: &mut String, done: impl Fn(&str) -> bool) -> bool {
    let end = Instant::now() + Duration::from_secs(5);
    let mut buf = [0u8; 256];
    while Instant::now() < end {
        if done(got) {
            return true;
        }
        match port.read(&mut buf) {
            Ok(n) if n > 0 => got.push_str(&String::from_utf8_lossy(&buf[..n])),
            _ => std::thread::sleep(Duration::from_millis(2)),
        }
    }
    done(got)
}

fn read_until(port: &mut std::fs::File, got: &mut String, want: &str) -> bool {
    read_while(port, got, |s| s.contains(want))
}

fn wait_for(path: &Path) {
    let end = Instant::now() + Duration::from_secs(10);
    while !path.exists() {
        assert!(
            Instant::now() < end,
            "serve did not create {}",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn a_sender_talks_to_the_simulated_port() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyINKSTEP");
    let child = Command::new(env!("CARGO_BIN_EXE_inkstep-sim"))
        .args(["serve", "--speed", "20", "--link"])
        .arg(&link)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let _guard = Killed(child);
    wait_for(&link);
    let mut port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(rustix::fs::OFlags::NONBLOCK.bits() as i32)
        .open(&link)
        .unwrap();
    let mut got = String::new();
    assert!(
        read_until(&mut port, &mut got, "Grbl 1.1h"),
        "welcome: {got:?}"
    );

    port.write_all(b"?").unwrap();
    assert!(
        read_until(&mut port, &mut got, "<Idle|MPos:0.000,0.000,0.000"),
        "status: {got:?}"
    );

    got.clear();
    port.write_all(b"G21 G90\nG1 X2 Y1 F1200\n").unwrap();
    let two_oks = |s: &str| s.matches("ok\r\n").count() >= 2;
    assert!(read_while(&mut port, &mut got, two_oks), "oks: {got:?}");

    // At 20x, 2.2 mm at 20 mm/s is over within a few tens of milliseconds.
    let end = Instant::now() + Duration::from_secs(5);
    loop {
        got.clear();
        port.write_all(b"?").unwrap();
        assert!(read_until(&mut port, &mut got, ">"), "status: {got:?}");
        if got.contains("<Idle|MPos:2.000,1.000,0.000") {
            break;
        }
        assert!(Instant::now() < end, "never reached X2 Y1: {got:?}");
        std::thread::sleep(Duration::from_millis(20));
    }

    got.clear();
    port.write_all(b"G5\n").unwrap();
    assert!(read_until(&mut port, &mut got, "error:"), "error: {got:?}");
}

use std::os::unix::fs::OpenOptionsExt;

/// Opening the port starts a session, as on the board (DTR): every client that opens
/// it gets the welcome line first, even one that comes after another has gone.
#[test]
fn each_client_that_opens_the_port_gets_the_welcome() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyINKSTEP");
    let child = Command::new(env!("CARGO_BIN_EXE_inkstep-sim"))
        .args(["serve", "--speed", "20", "--link"])
        .arg(&link)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let _guard = Killed(child);
    wait_for(&link);
    let open = || {
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(rustix::fs::OFlags::NONBLOCK.bits() as i32)
            .open(&link)
            .unwrap()
    };
    for _ in 0..2 {
        let mut port = open();
        let mut got = String::new();
        assert!(
            read_until(&mut port, &mut got, "Grbl 1.1h"),
            "welcome: {got:?}"
        );
        port.write_all(b"$I\n").unwrap();
        assert!(read_until(&mut port, &mut got, "ok\r\n"), "{got:?}");
        drop(port);
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A killed simulator must not leave its `--link` symlink dangling: SIGTERM (what
/// `kill` and service managers send) ends the serve loop normally, the exit status is
/// success and the link is gone.
#[test]
fn sigterm_ends_serve_and_removes_the_link() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyINKSTEP");
    let child = Command::new(env!("CARGO_BIN_EXE_inkstep-sim"))
        .args(["serve", "--link"])
        .arg(&link)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut guard = Killed(child);
    wait_for(&link);
    let pid = rustix::process::Pid::from_child(&guard.0);
    rustix::process::kill_process(pid, rustix::process::Signal::TERM).unwrap();
    let end = Instant::now() + Duration::from_secs(5);
    let status = loop {
        if let Some(s) = guard.0.try_wait().unwrap() {
            break s;
        }
        assert!(Instant::now() < end, "serve did not stop on SIGTERM");
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!(status.success(), "exit status {status:?}");
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "the link {} is still there",
        link.display()
    );
}
