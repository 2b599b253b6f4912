//! `inkstep-host send` end to end through a real pseudo-terminal, the way it
//! talks to the simulator (`cargo sim serve`) or a board: the fake Grbl
//! (tests/common) sits on the pty master in a thread, the real binary opens
//! the slave path with serialport, and the test checks the exit code, the
//! message and that the 128-byte buffer never overflowed.

mod common;

use common::FakeGrbl;
use inkstep_host::stream::streamer::Transport;
use std::ffi::CStr;
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread;
use std::time::Duration;

struct Pty {
    master: i32,
    slave: i32,
    path: String,
}

fn open_pty() -> Pty {
    let (mut master, mut slave) = (0, 0);
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(rc, 0, "openpty failed");
    let mut buf = [0 as libc::c_char; 256];
    assert_eq!(
        unsafe { libc::ttyname_r(slave, buf.as_mut_ptr(), buf.len()) },
        0
    );
    let path = unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    unsafe { libc::fcntl(master, libc::F_SETFL, libc::O_NONBLOCK) };
    Pty {
        master,
        slave,
        path,
    }
}

/// Runs the fake on the master side until `stop`; returns it for checks.
fn serve(master: i32, stop: Arc<AtomicBool>) -> thread::JoinHandle<FakeGrbl> {
    thread::spawn(move || {
        let mut g = FakeGrbl::new();
        let mut buf = [0u8; 256];
        while !stop.load(Ordering::Relaxed) {
            let n = unsafe { libc::read(master, buf.as_mut_ptr().cast(), buf.len()) };
            if n > 0 {
                g.send(&buf[..n as usize]).unwrap();
            }
            let m = g.recv(&mut buf).unwrap();
            let mut off = 0;
            while off < m {
                let w = unsafe { libc::write(master, buf[off..m].as_ptr().cast(), m - off) };
                if w > 0 {
                    off += w as usize;
                } else {
                    thread::sleep(Duration::from_micros(100));
                }
            }
            thread::sleep(Duration::from_micros(300));
        }
        g
    })
}

fn run_send(program: &str) -> (std::process::Output, FakeGrbl) {
    let pty = open_pty();
    let stop = Arc::new(AtomicBool::new(false));
    let h = serve(pty.master, stop.clone());
    let dir = std::env::temp_dir().join(format!(
        "inkstep-pty-{}-{}",
        std::process::id(),
        program.len()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("job.gcode");
    std::fs::write(&file, program).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
        .args([
            "send",
            file.to_str().unwrap(),
            "--port",
            &pty.path,
            "--status-hz",
            "20",
        ])
        .output()
        .unwrap();
    stop.store(true, Ordering::Relaxed);
    let g = h.join().unwrap();
    unsafe {
        libc::close(pty.slave);
        libc::close(pty.master);
    }
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
    assert_eq!(g.received.len(), 153);
    assert_eq!(g.received[2], "G1X0.25Y0.5F1200");
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
