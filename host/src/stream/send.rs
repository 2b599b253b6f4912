//! The `send` and `ports` commands: the serial port as the transport of
//! inkstep-serial's stream, an indicatif progress bar (lines, percent, ETA) with
//! the live state and position, and Ctrl-C wired to the stream's stop flag (feed
//! hold, then soft reset).

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use inkstep_serial::grbl::{alarm_text, error_text, Status};
use inkstep_serial::port::{self, Port};
use inkstep_serial::stream::{prepare, stream, Config, Observer, Outcome};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

struct Bar(ProgressBar);

impl Observer for Bar {
    fn progress(&mut self, acked: usize, total: usize) {
        self.0.set_length(total as u64);
        self.0.set_position(acked as u64);
    }
    fn status(&mut self, s: &Status) {
        let pos = s.pos.map_or(String::new(), |p| {
            format!(
                " {} X{:.2} Y{:.2} Z{:.2}",
                if s.work { "W" } else { "M" },
                p[0],
                p[1],
                p[2]
            )
        });
        self.0.set_message(format!("{}{}", s.state, pos));
    }
    fn message(&mut self, text: &str) {
        self.0.println(format!("[{text}]"));
    }
}

/// Streams `file` to `port`; an error, alarm or Ctrl-C is an Err naming the line.
pub fn run(file: &Path, port: &str, baud: u32, status_hz: f64) -> Result<()> {
    let program =
        std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let cfg = Config {
        status_interval: Duration::from_secs_f64(1.0 / status_hz.clamp(0.5, 50.0)),
        ..Config::default()
    };
    let lines = prepare(&program, cfg.rx_size).map_err(anyhow::Error::msg)?;
    let mut t = Port::open(port, baud).with_context(|| format!("opening {port}"))?;
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
    let mut bar = Bar(pb.clone());
    let outcome = stream(&mut t, &lines, &cfg, &stop, &mut bar)?;
    pb.finish();
    let name = file.display();
    match outcome {
        Outcome::Done { lines } => {
            println!("{name}: {lines} lines sent, all ok");
            Ok(())
        }
        Outcome::Error {
            file_line,
            text,
            code,
        } => {
            bail!("{name}:{file_line}: error:{code} ({}) on `{text}`; stopped (feed hold, soft reset)", error_text(code))
        }
        Outcome::Alarm { file_line, code } => {
            let at = file_line.map_or(String::new(), |l| format!(" at line {l}"));
            bail!(
                "{name}: ALARM:{code} ({}){at}; unlock with $X (re-home if position was lost)",
                alarm_text(code)
            )
        }
        Outcome::Interrupted { file_line } => {
            let at = file_line.map_or(String::new(), |l| format!(" at line {l}"));
            bail!("{name}: interrupted{at}: feed hold then soft reset sent")
        }
        Outcome::Locked { state } => {
            bail!("controller is in {state}: unlock with $X (or home with $H) first")
        }
        Outcome::Disconnected { file_line, error } => {
            let at = file_line.map_or(String::new(), |l| format!(" at line {l}"));
            bail!("{name}: connection lost{at}: {error}")
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
