//! `cargo host send --resume` end to end: the real binary streams a line of text to
//! the simulator behind a pty; the simulator goes away mid-job (a power cut: its
//! process ends), `send` says where to resume and remembers it in the state file;
//! a fresh simulator comes up at the same path and `send --resume` finishes the job
//! from that line, after which the state file forgets it.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

fn sim_at(link: &Path, speed: f64) -> (Arc<AtomicBool>, std::thread::JoinHandle<()>) {
    let stop = Arc::new(AtomicBool::new(false));
    let (l, s) = (link.to_path_buf(), stop.clone());
    let h = std::thread::spawn(move || {
        let _ = inkstep_sim::serve::serve(Some(&l), speed, || s.load(Ordering::Relaxed));
    });
    for _ in 0..100 {
        if link.exists() {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    (stop, h)
}

fn host(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_inkstep-host"));
    c.env("INKSTEP_STATE_DIR", dir);
    c
}

#[test]
fn send_resumes_a_job_after_the_board_went_away() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("inkstep-send-resume-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (link, job) = (dir.join("tty"), dir.join("job.nc"));
    let o = host(&dir)
        .args([
            "text",
            "Resume",
            "--size",
            "15",
            "-o",
            job.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (stop, sim) = sim_at(&link, 2.0);
    let send = host(&dir)
        .args([
            "send",
            job.to_str().unwrap(),
            "--port",
            link.to_str().unwrap(),
        ])
        .stderr(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    // A few seconds into the job, the board is gone.
    std::thread::sleep(Duration::from_secs(4));
    stop.store(true, Ordering::Relaxed);
    sim.join().unwrap();
    let o = send.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!o.status.success(), "the job cannot have finished: {err}");
    assert!(
        err.contains("connection lost") && err.contains("--from-line"),
        "{err}"
    );
    let state = std::fs::read_to_string(dir.join("resume.tsv")).unwrap();
    let line: usize = state.split('\t').next().unwrap().parse().unwrap();
    assert!(line > 5, "{state}");
    // The board is back (re-homed: a fresh simulator is at the origin).
    let (stop, sim) = sim_at(&link, 4.0);
    let o = host(&dir)
        .args([
            "send",
            job.to_str().unwrap(),
            "--port",
            link.to_str().unwrap(),
            "--resume",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{err}\n{out}");
    assert!(
        err.contains("resuming") && err.contains(&format!("at line {line}")),
        "{err}"
    );
    assert!(out.contains("all ok"), "{out}");
    assert!(
        !std::fs::read_to_string(dir.join("resume.tsv"))
            .unwrap()
            .contains("job.nc"),
        "forgotten once done"
    );
    // Nothing remembered now: --resume says so and sends nothing.
    let o = host(&dir)
        .args([
            "send",
            job.to_str().unwrap(),
            "--port",
            link.to_str().unwrap(),
            "--resume",
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no stopped run"));
    stop.store(true, Ordering::Relaxed);
    sim.join().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}

/// A layered job's pen change on a board that waits for cycle start: `send` says the
/// board holds, and Enter (a line on its stdin) continues it; without Enter the job
/// stays held, and the pen-down moves after the change are not drawn.
#[test]
fn send_continues_a_pen_change_when_enter_is_pressed() {
    use std::io::Write;
    let dir: PathBuf = std::env::temp_dir().join(format!("inkstep-send-m6-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (link, job) = (dir.join("tty"), dir.join("job.nc"));
    std::fs::write(
        &job,
        "G21 G90\nM3\nG1 X5 Y0 F1500\nM5\n(MSG,pen 2: red)\nM6 T2\nM3\nG1 X5 Y5\nM5\nG0 X0 Y0\n",
    )
    .unwrap();
    let (stop, sim) = sim_at(&link, 4.0);
    let mut send = host(&dir)
        .args([
            "send",
            job.to_str().unwrap(),
            "--port",
            link.to_str().unwrap(),
        ])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    // Held at the change: still running after a few seconds (the job takes well
    // under a second at 4x).
    std::thread::sleep(Duration::from_secs(3));
    assert!(
        send.try_wait().unwrap().is_none(),
        "the job waits for the user at M6"
    );
    send.stdin.as_mut().unwrap().write_all(b"\n").unwrap();
    let t0 = std::time::Instant::now();
    while send.try_wait().unwrap().is_none() {
        if t0.elapsed() > Duration::from_secs(20) {
            let _ = send.kill();
            panic!("Enter did not continue the pen change");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let o = send.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{err}\n{out}");
    assert!(
        err.contains("MSG:Pen change") && err.contains("press Enter"),
        "{err}"
    );
    assert!(out.contains("all ok"), "{out}");
    stop.store(true, Ordering::Relaxed);
    sim.join().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
