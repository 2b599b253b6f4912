//! The `send` and `ports` commands: the serial port as the transport of
//! inkstep-serial's stream, an indicatif progress bar (lines, percent, ETA) with
//! the live state and position, and Ctrl-C wired to the stream's stop flag (feed
//! hold, then soft reset). Before streaming it reads the board's settings (`$$`)
//! and prints the job time the firmware's planner gives with them; when a job
//! stops before its end it remembers the line to resume from (see
//! [`crate::resume`]), and `--from-line N` / `--resume` start there.

use crate::estimate::{self, fmt_time};
use crate::resume::{self, Seen};
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use inkstep_core::settings::Settings;
use inkstep_serial::grbl::{alarm_text, error_text, parse_reply, Reply, Status};
use inkstep_serial::port::{self, Port, Transport};
use inkstep_serial::stream::{prepare, stream, Config, Line, Observer, Outcome};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Lines that can be in flight at once: the receive buffer holds at most this
/// many (each at least a letter and its line end).
const MAX_IN_FLIGHT: usize = 64;

/// Lines up to which the estimate is made before sending (about a second).
const QUICK_LINES: usize = 50_000;

struct Bar {
    pb: ProgressBar,
    /// The estimate being made, and how it is worded when it is done.
    pending: Option<std::thread::JoinHandle<f64>>,
    say: Box<dyn Fn(f64) -> String>,
    seen: Seen,
    wco: [f64; 3],
    /// Enter pressed (a line on stdin): continue a hold.
    enter: Arc<AtomicBool>,
    /// The board holds (a pen change, `M0`, `!`): Enter continues it.
    held: bool,
}

impl Bar {
    fn note(&mut self, s: &Status) {
        if let Some(w) = s.wco {
            self.wco = w;
        }
        if let Some(p) = s.pos {
            self.seen.pos = Some(if s.work {
                p
            } else {
                [p[0] - self.wco[0], p[1] - self.wco[1], p[2] - self.wco[2]]
            });
        }
        if s.line.is_some() {
            self.seen.ln = s.line;
        }
    }
}

impl Observer for Bar {
    fn progress(&mut self, acked: usize, total: usize) {
        if self.pending.as_ref().is_some_and(|h| h.is_finished()) {
            if let Some(Ok(s)) = self.pending.take().map(|h| h.join()) {
                let text = (self.say)(s);
                self.message(&text);
            }
        }
        self.seen.acked = acked;
        self.pb.set_length(total as u64);
        self.pb.set_position(acked as u64);
    }
    fn status(&mut self, s: &Status) {
        self.note(s);
        let held = s.state.starts_with("Hold:0");
        if held && !self.held {
            self.message("holding (a pen change or M0 waits here): press Enter to continue, or cycle start / D on the board");
        }
        self.held = held;
        let pos = s.pos.map_or(String::new(), |p| {
            format!(
                " {} X{:.2} Y{:.2} Z{:.2}",
                if s.work { "W" } else { "M" },
                p[0],
                p[1],
                p[2]
            )
        });
        let ln = s.line.map_or(String::new(), |n| format!(" Ln {n}"));
        self.pb.set_message(format!("{}{}{ln}", s.state, pos));
    }
    fn cycle_start(&mut self) -> bool {
        // Enter counts only while the board holds: a key pressed while drawing is
        // not kept for the next pen change.
        self.enter.swap(false, Ordering::SeqCst) && self.held
    }
    fn message(&mut self, text: &str) {
        // Hidden when not on a terminal: the messages still go to stderr.
        if self.pb.is_hidden() {
            eprintln!("[{text}]");
        } else {
            self.pb.println(format!("[{text}]"));
        }
    }
}

/// Where to start a job.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum From {
    Start,
    /// At this file line (1-based), the state before it rebuilt.
    Line(usize),
    /// Where the last run of this file stopped (remembered).
    Remembered,
}

/// How `send` is asked to run.
pub struct SendOptions<'a> {
    pub file: &'a Path,
    pub port: &'a str,
    pub baud: u32,
    pub status_hz: f64,
    pub from: From,
}

/// A flag set by every line read from stdin (Enter on a terminal), read by a
/// background thread so the stream never waits for the keyboard.
fn enter_pressed() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    std::thread::spawn(move || {
        let mut line = String::new();
        while std::io::stdin().read_line(&mut line).is_ok_and(|n| n > 0) {
            f.store(true, Ordering::SeqCst);
            line.clear();
        }
    });
    flag
}

/// One status report asked for now (after a stop, for the final position).
fn last_status<T: Transport>(t: &mut T) -> Option<Status> {
    t.send(b"?").ok()?;
    let t0 = Instant::now();
    let mut pending = Vec::new();
    let mut buf = [0u8; 256];
    while t0.elapsed() < Duration::from_millis(500) {
        let n = t.recv(&mut buf).ok()?;
        pending.extend_from_slice(&buf[..n]);
        while let Some(i) = pending.iter().position(|&b| b == b'\n') {
            let line: Vec<u8> = pending.drain(..=i).collect();
            if let Reply::Status(s) = parse_reply(String::from_utf8_lossy(&line).trim()) {
                return Some(s);
            }
        }
    }
    None
}

/// Streams the file to the port; an error, alarm or Ctrl-C is an Err naming
/// the line, and the line to resume from is remembered.
pub fn run(o: &SendOptions) -> Result<()> {
    let file = o.file;
    let program =
        std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let cfg = Config {
        status_interval: Duration::from_secs_f64(1.0 / o.status_hz.clamp(0.5, 50.0)),
        ..Config::default()
    };
    // Checked before the port is touched: a bad file sends nothing.
    prepare(&program, cfg.rx_size).map_err(anyhow::Error::msg)?;
    let from = match o.from {
        From::Start => None,
        From::Line(n) => Some(n),
        From::Remembered => Some(resume::remembered(file).with_context(|| {
            format!(
                "no stopped run of {} is remembered (in {}): give --from-line N",
                file.display(),
                resume::state_file().map_or("-".into(), |f| f.display().to_string())
            )
        })?),
    };
    let mut t = Port::open(o.port, o.baud).with_context(|| format!("opening {}", o.port))?;
    // The board's settings: for the estimate, and for rebuilding a resumed
    // job's state exactly as the board's interpreter will.
    let settings = match estimate::read_settings(&mut t) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("settings not read ({e}): the firmware's defaults are assumed");
            Settings::default()
        }
    };
    let lines: Vec<Line> =
        match from {
            None => prepare(&program, cfg.rx_size).map_err(anyhow::Error::msg)?,
            Some(n) => {
                let l = resume::resume_lines(&program, n, &settings)?;
                eprintln!(
                "resuming {} at line {n}: the state before it rebuilt in {} lines, then the pen \
                 travels up to where line {n} starts and goes on",
                file.display(),
                l.iter().filter(|l| l.file_line == n).count().saturating_sub(1)
            );
                l
            }
        };
    let text: String = lines.iter().map(|l| format!("{}\n", l.text)).collect();
    let say = |job_s: f64| {
        format!(
            "estimated job time {} ({job_s:.3} s, the firmware's planner with the board's settings)",
            fmt_time(job_s)
        )
    };
    // A big job simulates for seconds: it starts at once and its estimate
    // is shown when ready.
    let mut pending = None;
    if lines.len() <= QUICK_LINES {
        let est = estimate::estimate(&text, &settings, crate::geom::Pt::new(0.0, 0.0), &[]);
        eprintln!("{}", say(est.job_s));
    } else {
        let s = settings.clone();
        pending = Some(std::thread::spawn(move || {
            estimate::estimate(&text, &s, crate::geom::Pt::new(0.0, 0.0), &[]).job_s
        }));
        eprintln!("estimating the job time while it runs…");
    }
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))
            .context("installing Ctrl-C handler")?;
    }
    let pb = ProgressBar::new(lines.len() as u64);
    pb.set_style(
        ProgressStyle::with_template(
            "{bar:30.cyan/blue} {pos}/{len} lines {percent:>3}% ETA {eta:>4} {msg}",
        )
        .expect("valid template"),
    );
    pb.enable_steady_tick(Duration::from_millis(200));
    let mut bar = Bar {
        pb: pb.clone(),
        pending,
        say: Box::new(say),
        seen: Seen::default(),
        wco: [0.0; 3],
        enter: enter_pressed(),
        held: false,
    };
    let outcome = stream(&mut t, &lines, &cfg, &stop, &mut bar)?;
    pb.finish();
    let name = file.display();
    // Where to resume, remembered for `--resume`.
    let remember = |bar: &mut Bar, t: &mut Port| -> String {
        if let Some(s) = last_status(t) {
            bar.note(&s);
        }
        bar.seen.sent = (bar.seen.acked + MAX_IN_FLIGHT).min(lines.len());
        let spans = resume::spans_of(&lines, &settings);
        match resume::resume_point(&spans, &bar.seen) {
            Some(n) => {
                let saved = resume::remember(file, Some(n));
                format!(
                    "\nresume with: cargo host send {name} --port {} --from-line {n} (or --resume){}",
                    o.port,
                    saved.err().map_or(String::new(), |e| format!(" [{e}]"))
                )
            }
            None => String::new(),
        }
    };
    match outcome {
        Outcome::Done { lines } => {
            let _ = resume::remember(file, None);
            println!("{name}: {lines} lines sent, all ok");
            Ok(())
        }
        Outcome::Error {
            file_line,
            text,
            code,
        } => {
            let r = remember(&mut bar, &mut t);
            bail!("{name}:{file_line}: error:{code} ({}) on `{text}`; stopped (feed hold, soft reset){r}", error_text(code))
        }
        Outcome::Alarm { file_line, code } => {
            let at = file_line.map_or(String::new(), |l| format!(" at line {l}"));
            let r = remember(&mut bar, &mut t);
            bail!(
                "{name}: ALARM:{code} ({}){at}; unlock with $X (re-home with $H if position was lost){r}",
                alarm_text(code)
            )
        }
        Outcome::Interrupted { file_line } => {
            let at = file_line.map_or(String::new(), |l| format!(" at line {l}"));
            let r = remember(&mut bar, &mut t);
            bail!("{name}: interrupted{at}: feed hold then soft reset sent{r}")
        }
        Outcome::Locked { state } => {
            bail!("controller is in {state}: unlock with $X (or home with $H) first")
        }
        Outcome::Disconnected { file_line, error } => {
            let at = file_line.map_or(String::new(), |l| format!(" at line {l}"));
            let r = remember(&mut bar, &mut t);
            bail!("{name}: connection lost{at}: {error}{r}")
        }
    }
}

/// Prints the serial ports the system knows.
pub fn list_ports() -> Result<()> {
    let ports = port::list().context("listing serial ports")?;
    if ports.is_empty() {
        println!(
            "no serial ports found (the simulator's pty is not listed: pass its path to --port)"
        );
    }
    for (name, kind) in ports {
        println!("{name}\t{kind}");
    }
    Ok(())
}
