//! `cargo emu ...`: the unmodified firmware image on the emulated Blue Pill
//! (emu/README.md has every command). Shaped like `cargo sim`.

use clap::{Parser, Subcommand};
use inkstep_emu::clock::{T_PER_MS, T_PER_S};
use inkstep_emu::cpu_model::CpuModel;
use inkstep_emu::session::{product_elf, Session};
use inkstep_emu::timeline::Timeline;
use inkstep_serial::sender::Flow;
use inkstep_sim::trace::TraceWriter;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "cargo emu",
    about = "inkstep's firmware image on an emulated STM32F103CB board"
)]
struct Cli {
    /// The chip on the board: `cb` (128 KB, what the image is built for) or `c8`
    /// (64 KB, same footprint: the image refuses to run on it, visibly).
    #[arg(long, global = true, value_enum, default_value_t = Chip::Cb)]
    chip: Chip,
    /// The cycle model: `typical` or `pessimistic` (emu/README.md, "Cycle model");
    /// default: $INKSTEP_EMU_CPU, else pessimistic. `bench` runs both.
    #[arg(long, global = true)]
    cpu: Option<String>,
    #[command(subcommand)]
    cmd: Cmd,
}

/// The pins beyond the USB cable: the output log and the inputs the outside drives.
#[derive(clap::Args)]
struct Io {
    /// Record every change of the output pins of the wiring table (PA0-PA10, PC13,
    /// PC15) as CSV `t_us,pin,value` (virtual µs from power-up), with a `PA8_us` row
    /// giving each servo pulse's width.
    #[arg(long, value_name = "OUT.csv")]
    pins: Option<PathBuf>,
    /// A limit/home switch at a position, e.g. `x-:-5.0mm` or `y+:120mm`: NC, it opens
    /// the axis's input (PB1 for X, PB3 for Y) while the axis is beyond it, counted
    /// in steps from power-up (repeatable).
    #[arg(long = "switch", value_name = "AXIS(+|-):POS")]
    switches: Vec<String>,
    /// Drive an input at a time from the start of the job, e.g. `1.5s:hold=low`,
    /// `2s:start=pulse`, `3s:estop=open`; inputs estop, limit-x, limit-y (open/closed),
    /// hold, start (low/high/pulse) (repeatable).
    #[arg(long = "input", value_name = "TIME:INPUT=STATE")]
    inputs: Vec<String>,
    /// A script of such input changes, one a line (`#` comments).
    #[arg(long = "input-script", value_name = "FILE")]
    script: Option<PathBuf>,
}

impl Io {
    /// Before boot: what to log and where the switches are.
    fn setup(&self, s: &mut Session) -> Result<(), String> {
        if self.pins.is_some() {
            for (w, add) in
                s.m.board()
                    .watch
                    .iter_mut()
                    .zip(inkstep_emu::pins::OUTPUT_WATCH)
            {
                *w |= add;
            }
        }
        let mut o = s.m.state().board.outside.clone();
        for sw in &self.switches {
            o.switches.push(inkstep_emu::pins::PosSwitch::parse(sw)?);
        }
        s.set_outside(o);
        Ok(())
    }

    /// At the start of the job: the input times count from here.
    fn start(&self, s: &mut Session) -> Result<(), String> {
        use inkstep_emu::pins::{InputEvent, Schedule};
        let mut events = Vec::new();
        for i in &self.inputs {
            events.extend(InputEvent::parse(i)?);
        }
        if let Some(p) = &self.script {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            events.extend(
                InputEvent::parse_script(&text).map_err(|e| format!("{}: {e}", p.display()))?,
            );
        }
        s.inputs = Schedule::new(events, s.now());
        Ok(())
    }

    fn finish(&self, s: &Session) -> Result<(), String> {
        if let Some(p) = &self.pins {
            let f = std::fs::File::create(p).map_err(|e| format!("{}: {e}", p.display()))?;
            inkstep_emu::pins::write_pin_log(
                &s.m.state().board.pin_changes,
                std::io::BufWriter::new(f),
            )
            .map_err(|e| format!("{}: {e}", p.display()))?;
        }
        Ok(())
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Chip {
    Cb,
    C8,
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
        /// Press this keypad script (the simulator's `--keys` language) on the key
        /// matrix before the file is streamed; its `lcd:NAME` pictures go to --lcd
        /// (or the current directory).
        #[arg(long)]
        keys: Option<String>,
        /// Count the instructions each function executes while the file is streamed
        /// (after boot) and print the top N per exception, inclusive and self, per
        /// G-code line.
        #[arg(long, value_name = "N")]
        profile: Option<usize>,
        /// Print each task's share of the CPU and the step events per second for every
        /// window of MS milliseconds of virtual time while the file runs.
        #[arg(long, value_name = "MS")]
        timeline: Option<u64>,
        /// Send real-time bytes at a time after the first step, e.g. `250ms:!`,
        /// `1.2s:~`, `700ms:0x91` (repeatable; as `cargo sim run --realtime`).
        #[arg(long = "realtime", value_name = "TIME:BYTES")]
        realtime: Vec<String>,
        #[command(flatten)]
        io: Io,
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
        #[command(flatten)]
        io: Io,
    },
    /// The simulator's demo on the emulated board: its keypad script pressed on the
    /// key matrix, its G-code streamed over USB, the LCD written as PNGs.
    Demo {
        #[arg(long, default_value = "out/emu-demo")]
        out: PathBuf,
        /// Play this keypad script instead (the simulator's `--keys` language).
        #[arg(long)]
        keys: Option<String>,
        #[arg(long)]
        elf: Option<PathBuf>,
        #[arg(long)]
        log: Option<PathBuf>,
        #[arg(long)]
        flash: Option<PathBuf>,
    },
    /// Stream the reference programs over USB for minutes of virtual time with the LCD
    /// running, asking `?` every 100 ms; fails if the watchdog ever fires.
    Soak {
        #[arg(long, default_value_t = 10.0)]
        minutes: f64,
        #[arg(long)]
        elf: Option<PathBuf>,
        #[arg(long)]
        log: Option<PathBuf>,
    },
    /// Figures from the real image: CPU load per task (idle, drawing star.nc), the `?`
    /// answer time, the highest sustained step-event rate, e-stop latency.
    Bench {
        #[arg(long)]
        elf: Option<PathBuf>,
    },
    /// The `?` answer time during long character-counting streams (one-step moves,
    /// ordinary moves, arcs): median, p99 and max; exits 1 if any answer took over 2 ms.
    Latency {
        /// Lines per stream.
        #[arg(long, default_value_t = 100_000)]
        lines: usize,
        /// The streams to run (repeatable; default all).
        #[arg(long = "load", value_enum)]
        loads: Vec<inkstep_emu::latency::Load>,
        /// A `?` every this many ms (the next only once the last is answered).
        #[arg(long, default_value_t = 10)]
        every_ms: u64,
        /// Print what the CPU ran during every answer over 2 ms.
        #[arg(long)]
        explain: bool,
        #[arg(long)]
        elf: Option<PathBuf>,
    },
    /// Run the on-target tests (tests/on_target.rs, defmt-test) on the emulated board;
    /// exits with the tests' status.
    Test {
        /// The test image (default: built with `cargo test --release --no-run`).
        #[arg(long)]
        elf: Option<PathBuf>,
        #[arg(long)]
        log: Option<PathBuf>,
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

/// Write the LCD as `dir/NAME.png`.
fn save_lcd(s: &Session, dir: &Path, name: &str) -> Result<(), String> {
    inkstep_emu::demo::save_lcd(s, dir, name).map(|_| ())
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
    keys: Option<&str>,
    profile: Option<usize>,
    timeline: Option<u64>,
    realtime: &[String],
    io: &Io,
) -> Result<ExitCode, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let elf = elf_or_build(elf)?;
    let mut s = Session::new(&elf, flash)?;
    s.m.state_mut().echo_log = log.is_none();
    io.setup(&mut s)?;
    s.boot()?;
    io.start(&mut s)?;
    s.realtime = realtime
        .iter()
        .map(|r| inkstep_sim::run::Realtime::parse(r))
        .collect::<Result<_, _>>()?;
    s.realtime.sort_by_key(|r| (r.after_step, r.at_us));
    if let Some(script) = keys {
        inkstep_emu::demo::play(&mut s, script, lcd.unwrap_or(Path::new(".")))?;
    }
    if profile.is_some() {
        let image = inkstep_emu::elf::Image::read(&elf)?;
        s.m.state_mut().profiler = Some(inkstep_emu::profiler::Profiler::new(
            &image,
            inkstep_emu::nvic::EXC_COUNT,
        )?);
    }
    let flow = if char_count {
        Flow::CharCount(128)
    } else {
        Flow::SendResponse
    };
    let mut next_lcd = s.now();
    let mut frame = 0;
    let mut windows = timeline.map(|ms| Timeline::new(&mut s, ms));
    let resets_before = s.m.state().watchdog_resets;
    let streamed = s.stream(&text, flow, RUN_LIMIT, |s| {
        if let Some(t) = windows.as_mut() {
            t.poll(s);
        }
        if let Some(dir) = lcd {
            if s.now() >= next_lcd {
                save_lcd(s, dir, &format!("{frame:04}"))?;
                frame += 1;
                next_lcd += T_PER_S;
            }
        }
        Ok(())
    });
    let result = streamed.and_then(|r| {
        let report = s.wait_idle_each(RUN_LIMIT, |s| {
            if let Some(t) = windows.as_mut() {
                t.poll(s);
            }
            Ok(())
        })?;
        Ok((r, report))
    });
    if let Some(dir) = lcd {
        save_lcd(&s, dir, "last")?;
    }
    if log.is_some() {
        write_log(&s, log)?;
    }
    if let Some(path) = trace {
        write_trace(&s, path)?;
    }
    io.finish(&s)?;
    let steps = &s.m.state().board.steps;
    let job = match (steps.first(), steps.last()) {
        (Some(a), Some(b)) => (b.t - a.t) as f64 / T_PER_S as f64,
        _ => 0.0,
    };
    let pos = s.m.state().board.pos;
    let (done, report) = match &result {
        Ok((r, report)) => (r, report),
        Err(e) => {
            eprintln!("error: {e}");
            return Ok(ExitCode::FAILURE);
        }
    };
    println!("{report}");
    println!(
        "{} lines, {} errors, {} alarms; {} step events, job time {job:.4} s, final position {},{},{}; {:.1} ms virtual",
        done.lines,
        done.errors.len(),
        done.alarms.len(),
        steps.len(),
        pos[0],
        pos[1],
        pos[2],
        s.now() as f64 / T_PER_MS as f64,
    );
    // The CPU stalls of flash programming between the first and the last step (the
    // settings saves of `$` lines in a job; the simulator does not model them).
    if let (Some(a), Some(b)) = (steps.first(), steps.last()) {
        let stalled: u64 =
            s.m.state()
                .board
                .flash_stalls
                .iter()
                .filter(|st| st.0 >= a.t && st.0 <= b.t)
                .map(|st| st.1)
                .sum();
        println!(
            "flash programming stalls during the job: {:.6} s",
            stalled as f64 / T_PER_S as f64
        );
    }
    // The step interrupt's late armings (steps delayed, none lost: the preparation
    // could not keep the step queue filled), as the firmware counts them.
    if let Some(late) = s
        .symbol("inkstep_late_step_armings")
        .and_then(|a| s.read_u32(a))
    {
        println!("late step armings since power-up: {late}");
    }
    for e in done.errors.iter().chain(&done.alarms) {
        println!("{e}");
    }
    // A watchdog reset mid-job restarts the firmware: the position and the job are
    // lost, and the run must not pass for a good one.
    let resets = s.m.state().watchdog_resets - resets_before;
    if resets > 0 {
        println!("watchdog resets during the job: {resets} (the firmware restarted)");
    }
    if let (Some(top), Some(p)) = (profile, s.m.state().profiler.as_ref()) {
        print!("{}", p.report(top, done.lines.max(1) as f64, "line"));
    }
    if let Some(t) = &windows {
        print!("{}", t.report());
    }
    Ok(
        if done.errors.is_empty() && done.alarms.is_empty() && resets == 0 {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        },
    )
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
    io: &Io,
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
    io.setup(&mut s)?;
    io.start(&mut s)?;
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
    io.finish(&s)?;
    write_log(&s, log)?;
    result.map(|()| ExitCode::SUCCESS)
}

fn cmd_demo(
    out: &Path,
    keys: Option<&str>,
    elf: Option<PathBuf>,
    log: Option<&Path>,
    flash: Option<&Path>,
) -> Result<ExitCode, String> {
    let elf = elf_or_build(elf)?;
    let mut s = Session::new(&elf, flash)?;
    s.m.state_mut().echo_log = log.is_none();
    let shots = match keys {
        Some(script) => inkstep_emu::demo::play(&mut s, script, out),
        None => inkstep_emu::demo::demo(&mut s, out),
    };
    if log.is_some() {
        write_log(&s, log)?;
    }
    let shots = shots?;
    println!(
        "{} LCD pictures in {} ({:.1} s of virtual time)",
        shots.len(),
        out.display(),
        s.now() as f64 / T_PER_S as f64
    );
    Ok(ExitCode::SUCCESS)
}

fn cmd_soak(minutes: f64, elf: Option<PathBuf>, log: Option<&Path>) -> Result<ExitCode, String> {
    let elf = elf_or_build(elf)?;
    let mut s = Session::new(&elf, None)?;
    s.m.state_mut().echo_log = log.is_none();
    let r = inkstep_emu::soak::soak(&mut s, minutes * 60.0);
    if log.is_some() {
        write_log(&s, log)?;
    }
    let r = r?;
    println!("{r}");
    for c in &r.complaints {
        println!("{c}");
    }
    Ok(if r.passed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn cmd_bench(elf: Option<PathBuf>) -> Result<ExitCode, String> {
    let elf = elf_or_build(elf)?;
    // Both cycle models, unless `--cpu` picked one.
    let models = match std::env::args().any(|a| a == "--cpu" || a.starts_with("--cpu=")) {
        true => vec![CpuModel::default_model()],
        false => vec![CpuModel::Typical, CpuModel::Pessimistic],
    };
    print!("{}", inkstep_emu::bench::run(&elf, &models)?);
    Ok(ExitCode::SUCCESS)
}

fn cmd_latency(
    lines: usize,
    loads: &[inkstep_emu::latency::Load],
    every_ms: u64,
    explain: bool,
    elf: Option<PathBuf>,
) -> Result<ExitCode, String> {
    use inkstep_emu::latency::{measure, Load, TABLE_HEAD};
    let elf = elf_or_build(elf)?;
    println!("{TABLE_HEAD}");
    let mut ok = true;
    let chosen = if loads.is_empty() {
        <Load as clap::ValueEnum>::value_variants()
    } else {
        loads
    };
    for &load in chosen {
        let l = measure(&elf, load, lines, every_ms * T_PER_MS, explain)?;
        println!("{}", l.row(load));
        eprintln!(
            "  from the sender's write: max {:.0} µs, {} over 2 ms",
            l.max_from_write as f64 / T_PER_MS as f64 * 1000.0,
            l.over_bound_from_write
        );
        for c in l.complaints.iter().take(5) {
            eprintln!("  {c}");
        }
        ok &= l.within_bound();
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn cmd_test(elf: Option<PathBuf>, log: Option<&Path>) -> Result<ExitCode, String> {
    use inkstep_emu::target_tests;
    let elf = match elf {
        Some(e) => e,
        None => target_tests::build()?,
    };
    let out = target_tests::run(&elf, log.is_none(), target_tests::LIMIT)?;
    if let Some(p) = log {
        std::fs::write(p, out.log.join("\n") + "\n")
            .map_err(|e| format!("{}: {e}", p.display()))?;
    }
    println!(
        "{}: {} after {:.1} ms of virtual time",
        if out.passed() { "passed" } else { "FAILED" },
        out.end,
        out.t as f64 / T_PER_MS as f64
    );
    Ok(if out.passed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let f_size = match cli.chip {
        Chip::Cb => inkstep_emu::board::F_SIZE_KB,
        Chip::C8 => inkstep_emu::board::F_SIZE_KB_C8,
    };
    inkstep_emu::board::DEFAULT_F_SIZE_KB.store(f_size, std::sync::atomic::Ordering::Relaxed);
    if let Some(m) = &cli.cpu {
        match CpuModel::parse(m) {
            Some(m) => CpuModel::set_default(m),
            None => {
                eprintln!("emu: --cpu {m}: expected `typical` or `pessimistic`");
                return ExitCode::from(2);
            }
        }
    }
    let r = match cli.cmd {
        Cmd::Run {
            file,
            elf,
            trace,
            lcd,
            char_count,
            log,
            flash,
            keys,
            profile,
            timeline,
            realtime,
            io,
        } => cmd_run(
            &file,
            elf,
            trace.as_deref(),
            lcd.as_deref(),
            char_count,
            log.as_deref(),
            flash.as_deref(),
            keys.as_deref(),
            profile,
            timeline,
            &realtime,
            &io,
        ),
        Cmd::Serve {
            elf,
            link,
            speed,
            trace,
            lcd,
            log,
            flash,
            io,
        } => cmd_serve(
            elf,
            &link,
            speed,
            trace.as_deref(),
            lcd.as_deref(),
            log.as_deref(),
            flash.as_deref(),
            &io,
        ),
        Cmd::Demo {
            out,
            keys,
            elf,
            log,
            flash,
        } => cmd_demo(&out, keys.as_deref(), elf, log.as_deref(), flash.as_deref()),
        Cmd::Soak { minutes, elf, log } => cmd_soak(minutes, elf, log.as_deref()),
        Cmd::Bench { elf } => cmd_bench(elf),
        Cmd::Latency {
            lines,
            loads,
            every_ms,
            explain,
            elf,
        } => cmd_latency(lines, &loads, every_ms, explain, elf),
        Cmd::Test { elf, log } => cmd_test(elf, log.as_deref()),
    };
    match r {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
