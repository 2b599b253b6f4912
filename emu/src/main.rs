//! `cargo emu ...`: the unmodified firmware image on the emulated Blue Pill
//! (emu/README.md has every command). Shaped like `cargo sim`.

use clap::{Parser, Subcommand};
use inkstep_emu::clock::{T_PER_MS, T_PER_S, T_PER_US};
use inkstep_emu::session::{product_elf, Session};
use inkstep_sim::sender::{Flow, Sender};
use inkstep_sim::trace::TraceWriter;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "cargo emu", about = "inkstep's firmware image on an emulated STM32F103CB board")]
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
}

fn elf_or_build(elf: Option<PathBuf>) -> Result<PathBuf, String> {
    match elf {
        Some(e) => Ok(e),
        None => product_elf(),
    }
}

fn write_log(s: &Session, log: Option<&Path>) -> Result<(), String> {
    let lines = s.m.state().log.as_ref().map(|l| l.lines.join("\n")).unwrap_or_default();
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
    let flow = if char_count { Flow::CharCount(128) } else { Flow::SendResponse };
    let mut sender = Sender::new(&text, flow);
    sender.received(banner.as_bytes());
    let start = s.now();
    let mut next_lcd = s.now();
    let mut frame = 0;
    let result = (|| -> Result<(), String> {
        while !sender.done() {
            let bytes = sender.to_send();
            s.send(&bytes);
            s.run_for(T_PER_MS)?;
            let got = s.take_received();
            sender.received(got.as_bytes());
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
    let steps = &s.m.state().board.steps;
    if let Some(path) = trace {
        let f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut w = TraceWriter::new(std::io::BufWriter::new(f), 144_000_000).map_err(|e| e.to_string())?;
        let t0 = steps.first().map_or(0, |st| st.t);
        for st in steps {
            w.row(st.t - t0, st.pos).map_err(|e| e.to_string())?;
        }
        w.finish().map_err(|e| e.to_string())?;
    }
    let job = match (steps.first(), steps.last()) {
        (Some(a), Some(b)) => (b.t - a.t) as f64 / T_PER_S as f64,
        _ => 0.0,
    };
    let pos = s.m.state().board.pos;
    println!(
        "{} lines, {} errors, {} alarms; {} step events, job time {job:.4} s, final position {},{},{}; {:.1} ms virtual",
        sender.total_lines(),
        sender.errors.len(),
        sender.alarms.len(),
        steps.len(),
        pos[0],
        pos[1],
        pos[2],
        s.now() as f64 / T_PER_MS as f64,
    );
    for e in &sender.errors {
        println!("line {}: {} -> {}", e.line_no, e.text, e.response);
    }
    for a in &sender.alarms {
        println!("{a}");
    }
    if let Err(e) = result {
        eprintln!("error: {e}");
        return Ok(ExitCode::FAILURE);
    }
    let _ = T_PER_US;
    Ok(if sender.errors.is_empty() && sender.alarms.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
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
        } => cmd_run(&file, elf, trace.as_deref(), lcd.as_deref(), char_count, log.as_deref(), flash.as_deref()),
    };
    match r {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
