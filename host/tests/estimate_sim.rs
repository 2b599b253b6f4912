//! `cargo host estimate` and `send`'s estimate against the job time the board itself
//! measures: star.nc and a line of text are streamed by the real `inkstep-host send`
//! through a pty to the simulator (`cargo sim serve`'s loop, virtual time following the
//! wall clock), which reports `[MSG:Job finished: T s]` at the program's end. The
//! estimate, printed before the first line is sent with the settings read from the
//! board, must be within 1 % of T; `estimate --port` reads the same settings and gives
//! the same figure, and the firmware's defaults (which the board no longer has) do not.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

struct Sim {
    stop: Arc<AtomicBool>,
    h: Option<std::thread::JoinHandle<()>>,
    link: PathBuf,
}

impl Sim {
    fn start(name: &str, speed: f64) -> Sim {
        let link =
            std::env::temp_dir().join(format!("inkstep-est-{}-{name}.pty", std::process::id()));
        let _ = std::fs::remove_file(&link);
        let stop = Arc::new(AtomicBool::new(false));
        let (l, s) = (link.clone(), stop.clone());
        let h = std::thread::spawn(move || {
            let _ = inkstep_sim::serve::serve(Some(&l), speed, || s.load(Ordering::Relaxed));
        });
        for _ in 0..100 {
            if link.exists() {
                break;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        Sim {
            stop,
            h: Some(h),
            link,
        }
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.h.take() {
            let _ = h.join();
        }
        let _ = std::fs::remove_file(&self.link);
    }
}

fn host(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
        // Where a stopped job is remembered: not the user's cache.
        .env(
            "INKSTEP_STATE_DIR",
            std::env::temp_dir().join("inkstep-est-state"),
        )
        .args(args)
        .output()
        .unwrap()
}

/// The number in "... (12.345 s" after `key`.
fn secs_after(text: &str, key: &str) -> Option<f64> {
    let rest = &text[text.find(key)? + key.len()..];
    let start = rest.find(|c: char| c.is_ascii_digit())?;
    let num: String = rest[start..]
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    num.parse().ok()
}

/// Streams `file` to a fresh simulator (after `setup` lines, settings the board then
/// has); returns (send's estimate, the board's job time, `estimate --port`'s figure).
fn measure(name: &str, file: &Path, setup: &str) -> (f64, f64, f64) {
    let sim = Sim::start(name, 1.0);
    let port = sim.link.to_str().unwrap();
    if !setup.is_empty() {
        let f =
            std::env::temp_dir().join(format!("inkstep-est-{}-{name}.setup", std::process::id()));
        std::fs::write(&f, setup).unwrap();
        let o = host(&["send", f.to_str().unwrap(), "--port", port]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let o = host(&["estimate", file.to_str().unwrap(), "--port", port]);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        o.status.success(),
        "{out} {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let by_port = secs_after(&out, "estimated job time").and_then(|_| {
        let k = out.find(" (")?;
        secs_after(&out[k..], "(")
    });
    let o = host(&["send", file.to_str().unwrap(), "--port", port]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    let est = secs_after(&err, "estimated job time").and_then(|_| {
        let k = err.find("estimated job time")?;
        let k = k + err[k..].find(" (")?;
        secs_after(&err[k..], "(")
    });
    let board = secs_after(&err, "[MSG:Job finished:");
    match (est, board, by_port) {
        (Some(e), Some(b), Some(p)) => (e, b, p),
        _ => panic!("{name}: no estimate or job time in:\n{err}\n{out}"),
    }
}

fn check(name: &str, file: &Path, setup: &str) {
    let (est, board, by_port) = measure(name, file, setup);
    let err = (est - board).abs() / board;
    eprintln!(
        "{name}: estimate {est:.3} s, the board's job time {board:.3} s: {:.2} %",
        err * 100.0
    );
    assert!(err < 0.01, "{name}: estimate {est} s vs {board} s");
    assert!(
        (by_port - est).abs() < 1e-3,
        "{name}: estimate --port {by_port} vs send's {est}"
    );
    // With the firmware's defaults instead of the board's settings the figure differs.
    let o = host(&["estimate", file.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let k = out.find(" (").unwrap();
    let default = secs_after(&out[k..], "(").unwrap();
    if !setup.is_empty() {
        assert!(
            (default - est).abs() > 0.05 * est,
            "{name}: {default} vs {est}"
        );
    }
}

#[test]
fn the_estimate_is_within_one_percent_of_the_boards_job_time() {
    let dir = std::env::temp_dir();
    // star.nc sets its own motion settings; M2 ends the program so the board
    // reports the job's time.
    let star =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../bench/star.nc"))
            .unwrap();
    let star_file = dir.join(format!("inkstep-est-{}-star.nc", std::process::id()));
    std::fs::write(&star_file, format!("{star}M2\n")).unwrap();
    // A line of text (pen lifts and drops, short strokes) on a board whose
    // acceleration and pen settings are not the defaults.
    let text_file = dir.join(format!("inkstep-est-{}-text.nc", std::process::id()));
    let o = host(&[
        "text",
        "Pen 42",
        "--size",
        "10",
        "-o",
        text_file.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = std::thread::spawn(move || check("star.nc", &star_file, ""));
    check("text", &text_file, "$120=120\n$121=120\n$112=300\n");
    a.join().unwrap();
}
