//! `cargo emu ...`: the unmodified firmware image on the emulated Blue Pill
//! (emu/README.md has every command). Shaped like `cargo sim`.

use clap::{Parser, Subcommand};
use inkstep_emu::clock::{T_PER_MS, T_PER_S};
use inkstep_emu::session::{product_elf, Session};
use inkstep_serial::grbl::Reply;
use inkstep_serial::sender::{Answer, Event, Flow, Sender};
use inkstep_sim::trace::TraceWriter;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "cargo emu",
    about = "inkstep's firmware image on an emulated STM32F103CB board"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Stream a G-code file through the emulated USB port with the project's sender.
    Run {
        file: PathBuf,
        /// The firmware ELF (default: build and run the release product image).
        #[arg(long)]
        elf: Option<PathBuf>,
        /// Write the step trace (t_us,x,y,z) read off the step pins as CSV.
        #[arg(long)]
        trace: Option<PathBuf>,
        /// Write the LCD (rebuilt from the SPI traffic) as PNGs into this folder.
        #[arg(long)]
        lcd: Option<PathBuf>,
        /// Use character counting (128-byte buffer) instead of send-response.
        #[arg(long)]
        char_count: bool,
        /// Write the decoded defmt log here instead of printing it.
        #[arg(long)]
        log: Option<PathBuf>,
        /// Keep the flash array in this file (settings survive between runs).
        #[arg(long)]
        flash: Option<PathBuf>,
    },
    /// Put the board's USB serial port on a pseudo-terminal any Grbl sender can open
    /// (DTR rises when it is opened); runs until killed.
    Serve {
        #[arg(long)]
        elf: Option<PathBuf>,
        /// Make this path a symlink to the port.
        #[arg(long)]
        link: PathBuf,
        /// Run virtual time this many times faster than real time.
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
        #[arg(long)]
        trace: Option<PathBuf>,
        #[arg(long)]
        lcd: Option<PathBuf>,
        #[arg(long)]
        log: Option<PathBuf>,
        #[arg(long)]
        flash: Option<PathBuf>,
    },
}

fn elf_or_build(elf: Option<PathBuf>) -> Result<PathBuf, String> {
    match elf {
        Some(e) => Ok(e),
        None => product_elf(),
    }
}

fn write_log(s: &Session, log: Option<&Path>) -> Result<(), String> {
    let lines =
        s.m.state()
            .log
            .as_ref()
            .map(|l| l.lines.join("\n"))
            .unwrap_or_default();
    match log {
        Some(p) => std::fs::write(p, lines + "\n").map_err(|e| format!("{}: {e}", p.display())),
        None => {
            eprintln!("--- defmt log ---\n{lines}");
            Ok(())
        }
    }
}

fn save_lcd(s: &Session, dir: &Path, name: &str) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let lcd = &s.m.state().board.lcd;
    inkstep_sim::lcd::save_png(|x, y| lcd.pixel(x, y), &dir.join(format!("{name}.png")))
}

/// Virtual time after which a run is abandoned.
const RUN_LIMIT: u64 = 3600 * T_PER_S;

#[allow(clippy::too_many_arguments)]
fn cmd_run(
    file: &Path,
    elf: Option<PathBuf>,
    trace: Option<&Path>,
    lcd: Option<&Path>,
    char_count: bool,
    log: Option<&Path>,
    flash: Option<&Path>,
) -> Result<ExitCode, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let elf = elf_or_build(elf)?;
    let mut s = Session::new(&elf, flash)?;
    s.boot()?;
    let banner = s.take_received();
    let flow = if char_count {
        Flow::CharCount(128)
    } else {
        Flow::SendResponse
    };
    let mut sender = Sender::new(flow);
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    for (i, l) in lines.iter().enumerate() {
        sender.push(i + 1, *l);
    }
    let mut errors: Vec<String> = Vec::new();
    let mut alarms: Vec<String> = Vec::new();
    let note = |events: Vec<Event<usize>>, errors: &mut Vec<String>, alarms: &mut Vec<String>| {
        for e in events {
            match e {
                Event::Answered(n, Answer::Error(code)) => {
                    errors.push(format!("line {n}: {} -> error:{code}", lines[n - 1]))
                }
                Event::Reply(Reply::Alarm(code)) => alarms.push(format!("ALARM:{code}")),
                _ => {}
            }
        }
    };
    note(sender.received(banner.as_bytes()), &mut errors, &mut alarms);
    let start = s.now();
    let mut next_lcd = s.now();
    let mut frame = 0;
    let result = (|| -> Result<(), String> {
        while !sender.done() {
            let bytes = sender.to_send();
            s.send(&bytes);
            // The sender reacts within one host-controller slot (125 µs), as a program
            // on the PC does; the USB timing model is in emu/README.md.
            s.run_for(inkstep_emu::usb_host::SLOT_T)?;
            let got = s.take_received();
            note(sender.received(got.as_bytes()), &mut errors, &mut alarms);
            if let Some(dir) = lcd {
                if s.now() >= next_lcd {
                    save_lcd(&s, dir, &format!("{frame:04}"))?;
                    frame += 1;
                    next_lcd += T_PER_S;
                }
            }
            if s.now() - start > RUN_LIMIT {
                return Err("the job did not finish within an hour of virtual time".into());
            }
        }
        let report = s.wait_idle(RUN_LIMIT)?;
        println!("{report}");
        Ok(())
    })();
    if let Some(dir) = lcd {
        save_lcd(&s, dir, "last")?;
    }
    write_log(&s, log)?;
    if let Some(path) = trace {
        write_trace(&s, path)?;
    }
    let steps = &s.m.state().board.steps;
    let job = match (steps.first(), steps.last()) {
        (Some(a), Some(b)) => (b.t - a.t) as f64 / T_PER_S as f64,
        _ => 0.0,
    };
    let pos = s.m.state().board.pos;
    println!(
        "{} lines, {} errors, {} alarms; {} step events, job time {job:.4} s, final position {},{},{}; {:.1} ms virtual",
        lines.len(),
        errors.len(),
        alarms.len(),
        steps.len(),
        pos[0],
        pos[1],
        pos[2],
        s.now() as f64 / T_PER_MS as f64,
    );
    for e in errors.iter().chain(&alarms) {
        println!("{e}");
    }
    if let Err(e) = result {
        eprintln!("error: {e}");
        return Ok(ExitCode::FAILURE);
    }
    Ok(if errors.is_empty() && alarms.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn write_trace(s: &Session, path: &Path) -> Result<(), String> {
    let steps = &s.m.state().board.steps;
    let f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut w =
        TraceWriter::new(std::io::BufWriter::new(f), 144_000_000).map_err(|e| e.to_string())?;
    let t0 = steps.first().map_or(0, |st| st.t);
    for st in steps {
        w.row(st.t - t0, st.pos).map_err(|e| e.to_string())?;
    }
    w.finish().map(|_| ()).map_err(|e| e.to_string())
}

#[allow(clippy::too_many_arguments)]
fn cmd_serve(
    elf: Option<PathBuf>,
    link: &Path,
    speed: f64,
    trace: Option<&Path>,
    lcd: Option<&Path>,
    log: Option<&Path>,
    flash: Option<&Path>,
) -> Result<ExitCode, String> {
    use inkstep_serial::pty::Pty;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    if !(speed > 0.0 && speed.is_finite()) {
        return Err("--speed must be a positive number".into());
    }
    let elf = elf_or_build(elf)?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .map_err(|e| format!("installing the signal handler: {e}"))?;
    let mut pty = Pty::open().map_err(|e| format!("pty: {e}"))?;
    pty.link_at(link)
        .map_err(|e| format!("{}: {e}", link.display()))?;
    let mut s = Session::new(&elf, flash)?;
    s.m.state_mut().echo_log = log.is_none();
    s.m.board().host.port_open = false;
    eprintln!(
        "emulated board on {} ({}), speed {speed}x; Ctrl-C ends",
        link.display(),
        pty.path().display()
    );
    let real0 = std::time::Instant::now();
    let virt0 = s.now();
    let mut lcd_writes = 0;
    let mut frame = 0;
    let mut buf = [0u8; 4096];
    let result = (|| -> Result<(), String> {
        while !stop.load(Ordering::Relaxed) {
            // DTR is up while a program has the port open.
            pty.client_events().map_err(|e| format!("pty: {e}"))?;
            s.m.board().host.port_open = pty.clients() > 0;
            let n = pty.read_available(&mut buf).map_err(|e| e.to_string())?;
            if n > 0 {
                s.send(&buf[..n]);
            }
            s.run_for(T_PER_MS)?;
            let out = s.take_received();
            if !out.is_empty() {
                pty.send(out.as_bytes()).map_err(|e| e.to_string())?;
            }
            pty.flush_pending().map_err(|e| e.to_string())?;
            if let Some(dir) = lcd {
                let w = s.m.state().board.lcd.writes;
                if w != lcd_writes {
                    lcd_writes = w;
                    save_lcd(&s, dir, &format!("{frame:05}"))?;
                    save_lcd(&s, dir, "last")?;
                    frame += 1;
                }
            }
            // Pace virtual time against the wall clock.
            let virt = (s.now() - virt0) as f64 / T_PER_S as f64;
            let real = real0.elapsed().as_secs_f64() * speed;
            if virt > real {
                std::thread::sleep(std::time::Duration::from_secs_f64((virt - real) / speed));
            }
        }
        Ok(())
    })();
    if let Some(p) = trace {
        write_trace(&s, p)?;
    }
    write_log(&s, log)?;
    result.map(|()| ExitCode::SUCCESS)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let r = match cli.cmd {
        Cmd::Run {
            file,
            elf,
            trace,
            lcd,
            char_count,
            log,
            flash,
        } => cmd_run(
            &file,
            elf,
            trace.as_deref(),
            lcd.as_deref(),
            char_count,
            log.as_deref(),
            flash.as_deref(),
        ),
        Cmd::Serve {
            elf,
            link,
            speed,
            trace,
            lcd,
            log,
            flash,
        } => cmd_serve(
            elf,
            &link,
            speed,
            trace.as_deref(),
            lcd.as_deref(),
            log.as_deref(),
            flash.as_deref(),
        ),
    };
    match r {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
