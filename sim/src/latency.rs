//! `cargo sim latency`: how long a `?` waits for its status report while a sender
//! streams a program with character counting, measured from the sender's side of a
//! serial port in wall-clock time, as a user's sender sees it.
//!
//! The client is a plain Grbl sender on a port path (inkstep-serial's sender and
//! port), so the same measurement runs against the simulator (`cargo sim serve`,
//! which this command starts itself, one fresh board per run) or against any other
//! board behind a port, such as the emulator's `cargo emu serve --link PATH`
//! (`--port PATH`). One `?` is outstanding at a time; the next goes out a fixed
//! interval after the answer. A `?` unanswered after a second counts as lost.

use inkstep_serial::grbl::Reply;
use inkstep_serial::port::{Port, Transport};
use inkstep_serial::sender::{Answer, Event, Flow, Sender};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A `?` unanswered this long is lost.
const LOST_AFTER: Duration = Duration::from_secs(1);

/// The programs streamed while `?` is timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Program {
    /// `G91 G1 X0.0125`: one step each (80 steps/mm), the protocol's busiest case.
    OneStep,
    /// A 20 mm circle in chords of one degree (0.35 mm), G90: a plotter's curves.
    Ordinary,
}

impl Program {
    pub fn name(self) -> &'static str {
        match self {
            Program::OneStep => "one-step moves",
            Program::Ordinary => "ordinary moves",
        }
    }

    /// The program's `n` lines.
    pub fn lines(self, n: usize) -> Vec<String> {
        let mut out = Vec::with_capacity(n);
        match self {
            Program::OneStep => {
                out.push("G21 G91 G1 F3000".to_string());
                out.extend((1..n).map(|_| "X0.0125".to_string()));
            }
            Program::Ordinary => {
                out.push("G21 G90 G1 F3000".to_string());
                out.extend((1..n).map(|i| {
                    let a = (i % 360) as f64 * std::f64::consts::PI / 180.0;
                    format!("X{:.3} Y{:.3}", 20.0 * a.cos(), 20.0 * a.sin())
                }));
            }
        }
        out
    }
}

/// What one stream measured.
#[derive(Clone, Debug, Default)]
pub struct Latency {
    /// Answer times of the `?`s, sorted, in seconds.
    pub answers: Vec<f64>,
    pub lost: usize,
    pub errors: usize,
    /// Lines answered, and the stream's wall-clock time.
    pub lines: usize,
    pub seconds: f64,
}

impl Latency {
    /// The `q`-quantile (nearest rank) of the answer times, in milliseconds.
    pub fn quantile_ms(&self, q: f64) -> f64 {
        if self.answers.is_empty() {
            return f64::NAN;
        }
        let i = ((self.answers.len() as f64 * q).ceil() as usize).clamp(1, self.answers.len());
        self.answers[i - 1] * 1e3
    }
}

/// Streams `lines` to the board on `port` with character counting (128 bytes) and
/// times a `?` every `interval` meanwhile. The board is reset first (0x18).
pub fn measure(port: &Path, lines: &[String], interval: Duration) -> Result<Latency, String> {
    let path = port.to_string_lossy();
    let mut port = Port::open(&path, 115_200).map_err(|e| format!("{path}: {e}"))?;
    let io = |e: std::io::Error| format!("{path}: {e}");
    // A clean start: reset, wait for the welcome line, then for the board to be quiet
    // (a power-up welcome may arrive before the reset's).
    port.send(b"\x18").map_err(io)?;
    let mut sender: Sender<usize> = Sender::new(Flow::CharCount(128));
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut buf = [0u8; 4096];
    let mut welcomed = false;
    let mut quiet_since = Instant::now();
    while !welcomed || quiet_since.elapsed() < Duration::from_millis(300) {
        if Instant::now() > deadline {
            return Err(format!("{path}: no welcome line after a reset"));
        }
        let n = port.recv(&mut buf).map_err(io)?;
        if n > 0 {
            quiet_since = Instant::now();
        }
        welcomed |= sender
            .received(&buf[..n])
            .iter()
            .any(|e| matches!(e, Event::Reply(Reply::Welcome(_))));
    }
    for (i, l) in lines.iter().enumerate() {
        sender.push(i, l.clone());
    }
    let mut out = Latency::default();
    let start = Instant::now();
    let mut asked: Option<Instant> = None;
    let mut next_ask = start;
    while !sender.done() {
        let bytes = sender.to_send();
        if !bytes.is_empty() {
            port.send(&bytes).map_err(io)?;
        }
        let now = Instant::now();
        match asked {
            None if now >= next_ask => {
                port.send(b"?").map_err(io)?;
                asked = Some(Instant::now());
            }
            Some(t) if now - t > LOST_AFTER => {
                out.lost += 1;
                asked = None;
                next_ask = now;
            }
            _ => {}
        }
        let n = port.recv(&mut buf).map_err(io)?;
        let got = Instant::now();
        for e in sender.received(&buf[..n]) {
            match e {
                Event::Answered(_, Answer::Ok) => out.lines += 1,
                Event::Answered(_, Answer::Error(_)) => {
                    out.lines += 1;
                    out.errors += 1;
                }
                Event::Reply(Reply::Status(_)) => {
                    if let Some(t) = asked.take() {
                        out.answers.push((got - t).as_secs_f64());
                        next_ask = got + interval;
                    }
                }
                Event::Reply(Reply::Welcome(w)) => {
                    return Err(format!("{path}: the board restarted mid-stream ({w})"))
                }
                _ => {}
            }
        }
    }
    out.seconds = start.elapsed().as_secs_f64();
    out.answers.sort_by(f64::total_cmp);
    // The moves still queued run out before the next stream (whose reset would
    // otherwise cut them: alarm 3).
    let deadline = Instant::now() + Duration::from_secs(600);
    loop {
        if Instant::now() > deadline {
            return Err(format!("{path}: not idle 10 minutes after the stream"));
        }
        port.send(b"?").map_err(io)?;
        std::thread::sleep(Duration::from_millis(20));
        let n = port.recv(&mut buf).map_err(io)?;
        let idle = sender
            .received(&buf[..n])
            .iter()
            .any(|e| matches!(e, Event::Reply(Reply::Status(st)) if st.state == "Idle"));
        if idle {
            return Ok(out);
        }
    }
}

/// The host's load average over the last 5 minutes (wall-clock answer times include
/// the host's scheduling: on a busy machine a process waits for a core).
fn host_load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().nth(1).map(str::to_string))
        .unwrap_or_else(|| "?".into())
}

/// A simulator serving a pty at a temporary path, killed when dropped.
struct Served {
    child: Child,
    dir: PathBuf,
}

impl Served {
    fn start(speed: f64) -> Result<Served, String> {
        let dir =
            std::env::temp_dir().join(format!("inkstep-latency-{}-{speed}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let link = dir.join("tty");
        let exe = std::env::current_exe().map_err(|e| e.to_string())?;
        let child = Command::new(exe)
            .args(["serve", "--speed", &speed.to_string(), "--link"])
            .arg(&link)
            .stdout(Stdio::null())
            .spawn()
            .map_err(|e| format!("starting the simulator: {e}"))?;
        let served = Served { child, dir };
        for _ in 0..200 {
            if link.exists() {
                return Ok(served);
            }
            std::thread::sleep(Duration::from_millis(25));
        }
        Err("the simulator made no port within 5 s".into())
    }

    fn port(&self) -> PathBuf {
        self.dir.join("tty")
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// The benchmark: every program at every speed on a fresh simulator (or on `port`,
/// where the speed is the board's business), one table row each.
pub fn run(
    lines: usize,
    speeds: &[f64],
    port: Option<&Path>,
    interval: Duration,
) -> Result<(), String> {
    println!(
        "`?` answer time during {lines}-line character-counting streams, a `?` every \
         {} ms after the last answer, wall clock at the sender",
        interval.as_millis()
    );
    println!(
        "| program | board | `?` | median ms | p99 ms | max ms | lost | errors | stream s | host load |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let boards: Vec<(String, Option<f64>)> = match port {
        Some(p) => vec![(p.display().to_string(), None)],
        None => speeds
            .iter()
            .map(|&s| (format!("sim --speed {s}"), Some(s)))
            .collect(),
    };
    let mut failed = false;
    for program in [Program::OneStep, Program::Ordinary] {
        let text = program.lines(lines);
        for (board, speed) in &boards {
            let served = speed.map(Served::start).transpose()?;
            let path = served
                .as_ref()
                .map_or_else(|| port.map(Path::to_path_buf), |s| Some(s.port()))
                .ok_or("no port")?;
            let r = measure(&path, &text, interval)?;
            failed |= r.lost > 0 || r.errors > 0 || r.lines != text.len();
            println!(
                "| {} | {board} | {} | {:.2} | {:.2} | {:.2} | {} | {} | {:.1} | {} |",
                program.name(),
                r.answers.len(),
                r.quantile_ms(0.5),
                r.quantile_ms(0.99),
                r.quantile_ms(1.0),
                r.lost,
                r.errors,
                r.seconds,
                host_load()
            );
        }
    }
    if failed {
        return Err("some `?` went unanswered, or lines failed".into());
    }
    Ok(())
}
