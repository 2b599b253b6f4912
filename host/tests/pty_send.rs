//! `inkstep-host send` end to end through a real pseudo-terminal, the way it
//! talks to the simulator (`cargo sim serve`) or a board: the fake Grbl
//! (tests/common) sits on the server side of inkstep-serial's pty in a thread, the real binary opens
//! the slave path with serialport, and the test checks the exit code, the
//! message and that the 128-byte buffer never overflowed.

mod common;

use common::FakeGrbl;
use inkstep_serial::port::Transport;
use inkstep_serial::pty::Pty;
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread;
use std::time::Duration;

/// Runs the fake on the server side of a pty until `stop`; returns it for checks.
fn serve(mut pty: Pty, stop: Arc<AtomicBool>) -> thread::JoinHandle<FakeGrbl> {
    thread::spawn(move || {
        let mut g = FakeGrbl::new();
        let mut buf = [0u8; 256];
        while !stop.load(Ordering::Relaxed) {
            let n = pty.read_available(&mut buf).unwrap();
            if n > 0 {
                g.send(&buf[..n]).unwrap();
            }
            let m = g.recv(&mut buf).unwrap();
            pty.send(&buf[..m]).unwrap();
            thread::sleep(Duration::from_micros(300));
        }
        g
    })
}

fn run_send(program: &str) -> (std::process::Output, FakeGrbl) {
    let pty = Pty::open().unwrap();
    let path = pty.path().to_str().unwrap().to_string();
    let stop = Arc::new(AtomicBool::new(false));
    let h = serve(pty, stop.clone());
    let dir = std::env::temp_dir().join(format!(
        "inkstep-pty-{}-{}",
        std::process::id(),
        program.len()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("job.gcode");
    std::fs::write(&file, program).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
        // Where a stopped job is remembered: not the user's cache.
        .env("INKSTEP_STATE_DIR", &dir)
        .args([
            "send",
            file.to_str().unwrap(),
            "--port",
            &path,
            "--status-hz",
            "20",
        ])
        .output()
        .unwrap();
    stop.store(true, Ordering::Relaxed);
    let g = h.join().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (out, g)
}

fn program(n: usize) -> String {
    let mut s = String::from("G21 G90\nM5\n");
    for i in 0..n {
        s.push_str(&format!(
            "G1 X{}.25 Y{}.5 F1200 (segment {i})\n",
            i % 50,
            i % 7
        ));
    }
    s.push_str("M2\n");
    s
}

#[test]
fn send_streams_a_whole_file_over_a_pty() {
    let (out, g) = run_send(&program(150));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("153 lines sent, all ok"), "{stdout}");
    // First the settings, read for the estimate, then the program.
    assert_eq!(g.received.len(), 154);
    assert_eq!(g.received[0], "$$");
    assert_eq!(g.received[3], "G1X0.25Y0.5F1200");
    assert!(!g.overflow);
    assert!(g.max_fill > 100, "{}", g.max_fill);
}

#[test]
fn send_stops_on_error_and_names_the_line() {
    let prog = program(150).replacen("G1 X40.25", "G999 X40.25", 1);
    let (out, g) = run_send(&prog);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("job.gcode:43: error:20"), "{stderr}");
    assert!(
        stderr.contains("unsupported or invalid g-code command"),
        "{stderr}"
    );
    assert!(g.realtime.contains(&b'!') && g.realtime.contains(&0x18));
    assert!(!g.overflow);
}
