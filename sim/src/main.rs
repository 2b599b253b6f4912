//! `cargo sim ...`: the simulator's command line. Parses arguments and calls the
//! library; every command's work lives in a module of its own.

use clap::{Parser, Subcommand};
use inkstep_core::settings::Settings;
use inkstep_sim::board::{Board, TICK_HZ};
use inkstep_sim::run::Flow;
use inkstep_sim::trace::{Trace, TraceWriter};
use inkstep_sim::{bench, demo, grbl_model, kinematics, paths, plot, profiles, run};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `println!` that ends the program quietly when stdout is closed (`| head`).
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($t)*).is_err() {
            std::process::exit(0);
        }
    }};
}

#[derive(Parser)]
#[command(
    name = "cargo sim",
    about = "inkstep's simulator: the firmware core on a PC, in virtual time"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Stream a G-code file through the protocol at full speed in virtual time.
    Run {
        file: PathBuf,
        /// Write the step trace (t_us,x,y,z) as CSV.
        #[arg(long)]
        trace: Option<PathBuf>,
        /// Write the drawing as PNG.
        #[arg(long)]
        png: Option<PathBuf>,
        /// Write the drawing as SVG.
        #[arg(long)]
        svg: Option<PathBuf>,
        /// Write the LCD as PNGs into this folder while the file runs.
        #[arg(long)]
        lcd: Option<PathBuf>,
        /// With --lcd: one screen every this many milliseconds of virtual time.
        #[arg(long, default_value_t = 1000)]
        lcd_every: u64,
        /// Use character counting (128-byte buffer) instead of send-response.
        #[arg(long)]
        char_count: bool,
        /// Send real-time bytes at a time after the first step, e.g. `250ms:!`,
        /// `1.2s:~`, `700ms:0x91` (repeatable; as `cargo emu run --realtime`).
        #[arg(long = "realtime", value_name = "TIME:BYTES")]
        realtime: Vec<String>,
    },
    /// Run the reference programs of bench/ and compare with Grbl's figures.
    Bench {
        /// Folder of the reference programs, their ideal paths and Grbl's figures
        /// (default: the repository's bench/).
        #[arg(long)]
        dir: Option<PathBuf>,
    },
    /// Grbl's job time for G-code files from the model of Grbl 1.1's planner (15 blocks
    /// of look-ahead, trapezoids), as rows of bench/GRBL.md's model table.
    GrblModel { files: Vec<PathBuf> },
    /// Open a pseudo-terminal that behaves like the board's USB serial port; runs until killed.
    Serve {
        /// Also make this path a symlink to the port.
        #[arg(long)]
        link: Option<PathBuf>,
        /// Run virtual time this many times faster than real time.
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
    },
    /// How long a `?` waits for its report during long character-counting streams (of
    /// one-step moves and of ordinary moves), on fresh simulators at each speed, or on
    /// the board behind --port (e.g. `cargo emu serve --link PATH`).
    Latency {
        /// Lines per stream.
        #[arg(long, default_value_t = 100_000)]
        lines: usize,
        /// Virtual speeds of the simulators, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "1,10,100")]
        speeds: Vec<f64>,
        /// Measure the board behind this port instead of starting simulators.
        #[arg(long)]
        port: Option<PathBuf>,
        /// Milliseconds between an answer and the next `?`.
        #[arg(long, default_value_t = 10)]
        interval_ms: u64,
    },
    /// The standalone demo: boot, menu, sine with preview, star, then a G-code program;
    /// writes LCD screens, the drawing (PNG, SVG) and prints a summary.
    Demo {
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
        /// Play this keypad script instead of the demo's (see `keys` in the README:
        /// key names, NUMBERS, KEY:MS holds, wait:MS, idle, lcd:NAME).
        #[arg(long)]
        keys: Option<String>,
    },
    /// Plot path speed and per-axis acceleration of a step trace.
    Plot {
        trace: PathBuf,
        #[arg(short, long, default_value = "speed.png")]
        out: PathBuf,
        /// Steps per mm of X, Y, Z.
        #[arg(long, default_value_t = 80.0)]
        steps_per_mm: f64,
    },
    /// Plot the thesis's four acceleration profiles over the same distance.
    Profiles {
        #[arg(short, long, default_value = "profiles.png")]
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let r = match cli.cmd {
        Cmd::Run {
            file,
            trace,
            png,
            svg,
            lcd,
            lcd_every,
            char_count,
            realtime,
        } => {
            let outs = RunOutputs {
                trace: trace.as_deref(),
                png: png.as_deref(),
                svg: svg.as_deref(),
                lcd: lcd.as_deref(),
            };
            match realtime
                .iter()
                .map(|r| run::Realtime::parse(r))
                .collect::<Result<Vec<_>, _>>()
            {
                Ok(rt) => cmd_run(&file, outs, lcd_every.max(1), char_count, &rt),
                Err(e) => Err(e),
            }
        }
        Cmd::Bench { dir } => cmd_bench(dir),
        Cmd::GrblModel { files } => cmd_grbl_model(&files),
        Cmd::Demo { out, keys } => cmd_demo(&out, keys.as_deref()),
        Cmd::Latency {
            lines,
            speeds,
            port,
            interval_ms,
        } => inkstep_sim::latency::run(
            lines,
            &speeds,
            port.as_deref(),
            std::time::Duration::from_millis(interval_ms),
        )
        .map(|()| ExitCode::SUCCESS),
        Cmd::Serve { link, speed } => {
            if !(speed > 0.0 && speed.is_finite()) {
                return fail("--speed must be a positive number");
            }
            // Ctrl-C, SIGTERM or SIGHUP end the loop normally, so the pty is dropped and
            // the `--link` symlink removed instead of left dangling.
            let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            let flag = stop.clone();
            if let Err(e) =
                ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed))
            {
                return fail(&format!("installing the signal handler: {e}"));
            }
            inkstep_sim::serve::serve(link.as_deref(), speed, || {
                stop.load(std::sync::atomic::Ordering::Relaxed)
            })
            .map(|()| ExitCode::SUCCESS)
        }
        Cmd::Plot {
            trace,
            out,
            steps_per_mm,
        } => plot_trace(&trace, &out, steps_per_mm),
        Cmd::Profiles { out } => plot_profiles(&out),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn fail(msg: &str) -> ExitCode {
    eprintln!("error: {msg}");
    ExitCode::from(2)
}

struct RunOutputs<'a> {
    trace: Option<&'a Path>,
    png: Option<&'a Path>,
    svg: Option<&'a Path>,
    lcd: Option<&'a Path>,
}

fn cmd_run(
    file: &Path,
    outs: RunOutputs,
    lcd_every: u64,
    char_count: bool,
    realtime: &[run::Realtime],
) -> Result<ExitCode, String> {
    let RunOutputs {
        trace,
        png,
        svg,
        lcd,
    } = outs;
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let flow = if char_count {
        Flow::CharCount(inkstep_core::protocol::RX_BUFFER_SIZE)
    } else {
        Flow::SendResponse
    };
    let r = match lcd {
        None => run::run_on_timed(
            &mut Board::new(Settings::default()),
            &text,
            flow,
            realtime,
            &mut |_| {},
        ),
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            let mut board = Board::new(Settings::default()).with_lcd();
            let every = Board::ms_to_ticks(lcd_every);
            let mut next = 0u64;
            let mut n = 0u32;
            let mut failed: Option<String> = None;
            let mut shoot = |b: &mut Board, force: bool| {
                if (force || b.now() >= next) && failed.is_none() {
                    n += 1;
                    if let Err(e) = demo::snapshot(b, &dir.join(format!("lcd_{n:04}.png"))) {
                        failed = Some(e);
                    }
                    next = b.now() + every;
                }
            };
            let r = run::run_on_timed(&mut board, &text, flow, realtime, &mut |b| shoot(b, false));
            shoot(&mut board, true);
            if let Some(e) = failed {
                return Err(e);
            }
            r
        }
    };
    if let Some(path) = trace {
        let f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut w =
            TraceWriter::new(std::io::BufWriter::new(f), TICK_HZ).map_err(|e| e.to_string())?;
        for e in &r.events {
            w.row(r.rel(e.t), e.pos).map_err(|e| e.to_string())?;
        }
        w.finish().map_err(|e| e.to_string())?;
    }
    let drawing = r.drawing();
    if let Some(path) = png {
        drawing.write_png(path, 1000)?;
    }
    if let Some(path) = svg {
        std::fs::write(path, drawing.to_svg()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let steps: [u32; 3] =
        [0, 1, 2].map(|a| r.events.iter().filter(|e| e.step & (1 << a) != 0).count() as u32);
    say!(
        "{}: {} lines, job time {:.4} s, steps X {} Y {} Z {}, final position {},{},{}",
        file.display(),
        r.lines,
        r.job_time_s(),
        steps[0],
        steps[1],
        steps[2],
        r.final_pos[0],
        r.final_pos[1],
        r.final_pos[2]
    );
    for m in &r.messages {
        say!("{m}");
    }
    for e in &r.errors {
        eprintln!("line {}: {} -> {}", e.line_no, e.text, e.response);
    }
    for a in &r.alarms {
        eprintln!("{a}");
    }
    if r.timed_out {
        eprintln!("the job did not finish within the virtual time limit");
    }
    if let Some((at, made)) = r.realtime_waiting {
        eprintln!(
            "a real-time byte was never sent: it is timed from step event #{at}, and the job made {made}"
        );
    }
    Ok(if r.ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn cmd_demo(out: &Path, keys: Option<&str>) -> Result<ExitCode, String> {
    let started = std::time::Instant::now();
    let s = match keys {
        None => demo::demo(out)?,
        Some(script) => {
            std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
            let mut s = demo::Session::new();
            s.play(script, out)?;
            s.part("keypad script", 0);
            demo::write_drawing(&s, out)?;
            s
        }
    };
    say!(
        "inkstep demo: {} LCD screens, drawing.png and drawing.svg in {}",
        s.shots.len(),
        out.display()
    );
    for (what, a, b, steps) in &s.parts {
        say!(
            "  {what:<24} job time {:>7.3} s, {steps} steps",
            (b - a) as f64 / TICK_HZ as f64
        );
    }
    let pos = s.board.pipeline.side().exec.position();
    say!(
        "  virtual time {:.1} s, final position {},{},{} steps; ran in {:.2} s",
        s.board.now() as f64 / TICK_HZ as f64,
        pos[0],
        pos[1],
        pos[2],
        started.elapsed().as_secs_f64()
    );
    Ok(ExitCode::SUCCESS)
}

fn cmd_bench(dir: Option<PathBuf>) -> Result<ExitCode, String> {
    let dir = dir.unwrap_or_else(paths::bench_dir);
    let runs = bench::run_all(&dir)?;
    let rows: Vec<(bench::GrblRow, bench::Figures)> = runs
        .iter()
        .map(|b| (b.grbl.clone(), b.ours.clone()))
        .collect();
    say!("{}", bench::markdown_table(&rows));
    say!("{}", bench::model_table(&runs));
    let failed = runs
        .iter()
        .any(|b| !b.run.ok() || !bench::goal_failures(&b.ours, &b.grbl).is_empty());
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn cmd_grbl_model(files: &[PathBuf]) -> Result<ExitCode, String> {
    let start_speed = f64::from(Settings::default().start_rate()) / 60.0;
    for f in files {
        let text = std::fs::read_to_string(f).map_err(|e| format!("{}: {e}", f.display()))?;
        let m =
            grbl_model::times(&text, start_speed).map_err(|e| format!("{}: {e}", f.display()))?;
        let name = f
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        say!(
            "| {name} | {:.4} | - | - | {} | {} | {},{} |",
            m.grbl,
            m.steps[0],
            m.steps[1],
            m.end[0],
            m.end[1]
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn plot_trace(path: &Path, out: &Path, spm: f64) -> Result<ExitCode, String> {
    let trace = Trace::read_file(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let k = kinematics::from_trace(&trace, [spm; 3], 0.001, 0.005, 0.02);
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    plot::trace_plot(&k, &format!("{name}: speed and acceleration"), out)?;
    say!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

fn plot_profiles(out: &Path) -> Result<ExitCode, String> {
    let p = profiles::THESIS;
    let profs: Vec<profiles::Profile> = profiles::FOUR
        .iter()
        .map(|&r| profiles::Profile::same_distance(r, &p))
        .collect();
    let t_end = profs.iter().map(|p| p.total()).fold(0.0, f64::max);
    let curves: Vec<plot::ProfileCurves> = profs
        .iter()
        .map(|prof| {
            let [t, v, a, x] = prof.sample(&p, t_end / 2000.0, prof.total());
            plot::ProfileCurves {
                name: format!("{} {:.2} ms", prof.ramp.name(), prof.total() * 1e3),
                t: t.into_iter().map(|t| t * 1e3).collect(),
                v,
                a,
                x,
            }
        })
        .collect();
    let title = format!(
        "Acceleration profiles over the same distance ({} -> {} mm/s, {} mm/s² limit; speed jumps clipped)",
        p.v_start, p.v_max, p.a_max
    );
    plot::profiles_plot(
        &curves,
        ["mm/s", "mm/s²", "mm"],
        "time (ms)",
        1.5 * p.a_max,
        &title,
        out,
    )?;
    say!("wrote {}", out.display());
    for prof in &profs {
        say!(
            "{:<20} ramp {:.3} ms, cruise {:.3} ms, total {:.3} ms",
            prof.ramp.name(),
            prof.t_ramp * 1e3,
            prof.t_cruise * 1e3,
            prof.total() * 1e3
        );
    }
    Ok(ExitCode::SUCCESS)
}
