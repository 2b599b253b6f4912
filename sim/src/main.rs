//! `cargo sim ...`: the simulator's command line. Parses arguments and calls the
//! library; every command's work lives in a module of its own.

use clap::{Parser, Subcommand};
use inkstep_sim::{kinematics, plot, profiles, trace::Trace};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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

fn plot_trace(path: &Path, out: &Path, spm: f64) -> Result<ExitCode, String> {
    let trace = Trace::read_file(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let k = kinematics::from_trace(&trace, [spm; 3], 0.001, 0.005);
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    plot::trace_plot(&k, &format!("{name}: speed and acceleration"), out)?;
    println!("wrote {}", out.display());
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
            let ms = |v: Vec<f64>| v.into_iter().map(|t| t * 1e3).collect();
            plot::ProfileCurves {
                name: format!("{} {:.2} ms", prof.ramp.name(), prof.total() * 1e3),
                t: ms(t.clone()),
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
    println!("wrote {}", out.display());
    for prof in &profs {
        println!(
            "{:<20} ramp {:.3} ms, cruise {:.3} ms, total {:.3} ms",
            prof.ramp.name(),
            prof.t_ramp * 1e3,
            prof.t_cruise * 1e3,
            prof.total() * 1e3
        );
    }
    Ok(ExitCode::SUCCESS)
}
