//! The `cargo host` command line: argument parsing and glue only; the work
//! is done by the library modules.
use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use inkstep_host::gcode_out::{to_gcode, GcodeOptions, Pen};
use inkstep_host::geom::{pen_up_travel, Pt, Stroke};
use inkstep_host::plan::{plan, PlanOptions};
use inkstep_host::{bench, preview, stream, svg_in, text, toolpath};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "inkstep-host",
    about = "inkstep's PC tool: stream G-code, text and SVG to G-code, previews"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Stream a G-code file to the board (or the simulator's pty) with
    /// Grbl character counting.
    Send {
        file: PathBuf,
        /// Serial port, e.g. /dev/ttyACM0 or the simulator's pty.
        #[arg(long)]
        port: String,
        #[arg(long, default_value_t = 115200)]
        baud: u32,
        /// Status polls ('?') per second.
        #[arg(long, default_value_t = 5.0)]
        status_hz: f64,
    },
    /// List serial ports.
    Ports,
    /// Text to G-code: Latin in a Hershey font, Chinese from stroke medians.
    Text {
        text: String,
        /// Character box in mm.
        #[arg(long, default_value_t = 20.0)]
        size: f64,
        /// Hershey font for Latin: futural, scripts, cursive, futuram.
        #[arg(long, default_value = "futural")]
        font: String,
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        out: OutArgs,
    },
    /// SVG to G-code: paths and shapes, transforms applied, curves flattened.
    Svg {
        file: PathBuf,
        /// Largest distance of a curve from its flattened polyline (mm).
        #[arg(long, default_value_t = 0.05)]
        tolerance: f64,
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Render G-code to PNG: pen-down strokes blue, pen-up travel red dashed.
    Preview {
        file: PathBuf,
        #[arg(short, long)]
        output: PathBuf,
        /// Image width in pixels.
        #[arg(long, default_value_t = 1600)]
        width: u32,
    },
    /// Pen-up travel of natural, greedy, inkstep and vpype orders on a text.
    PlanBench {
        #[arg(default_value = bench::DEFAULT_TEXT)]
        text: String,
        /// vpype command to compare with ("" to skip).
        #[arg(long, default_value = "vpype")]
        vpype: String,
        /// Iterated-local-search kicks.
        #[arg(long, default_value_t = 200)]
        kicks: usize,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum PenMode {
    /// M3 drops the pen, M5 lifts it (the firmware maps them per its settings).
    M3,
    /// Move the Z axis between --z-up and --z-down.
    Z,
}

/// G-code and planning options shared by `text` and `svg`.
#[derive(Args)]
struct OutArgs {
    #[arg(long, value_enum, default_value = "m3")]
    pen: PenMode,
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true)]
    z_up: f64,
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    z_down: f64,
    /// Z feed for pen drops (mm/min).
    #[arg(long, default_value_t = 600.0)]
    z_feed: f64,
    /// Drawing feed (mm/min).
    #[arg(long, default_value_t = 1500.0)]
    feed: f64,
    /// Dwell after each pen lift or drop (s).
    #[arg(long, default_value_t = 0.0)]
    dwell: f64,
    /// Pen start position "X,Y" in mm (the plan starts there, the job ends there).
    #[arg(long, default_value = "0,0", value_parser = parse_pt, allow_hyphen_values = true)]
    start: Pt,
    /// Keep the strokes in the given order (no planning).
    #[arg(long)]
    no_plan: bool,
    /// Never reverse a stroke (keeps calligraphic direction).
    #[arg(long)]
    keep_direction: bool,
    /// Do not join strokes that share end points.
    #[arg(long)]
    no_join: bool,
}

fn parse_pt(s: &str) -> Result<Pt, String> {
    let (x, y) = s.split_once(',').ok_or("expected X,Y")?;
    Ok(Pt::new(
        x.trim().parse().map_err(|_| "bad X")?,
        y.trim().parse().map_err(|_| "bad Y")?,
    ))
}

fn write_program(strokes: &[Stroke], a: &OutArgs, output: &PathBuf) -> Result<()> {
    let before = pen_up_travel(strokes, a.start);
    let ordered = if a.no_plan {
        strokes.to_vec()
    } else {
        let opts = PlanOptions {
            reverse: !a.keep_direction,
            join: !a.no_join,
            ..PlanOptions::default()
        };
        plan(strokes, a.start, &opts)
    };
    let pen = match a.pen {
        PenMode::M3 => Pen::M3,
        PenMode::Z => Pen::Z {
            up: a.z_up,
            down: a.z_down,
            feed: a.z_feed,
        },
    };
    let o = GcodeOptions {
        pen,
        feed: a.feed,
        dwell: a.dwell,
        home: a.start,
    };
    let g = to_gcode(&ordered, &o);
    std::fs::write(output, &g).with_context(|| format!("writing {}", output.display()))?;
    eprintln!(
        "{}: {} strokes in, {} out; pen-up travel {:.1} mm (as given {:.1} mm); {} lines",
        output.display(),
        strokes.len(),
        ordered.len(),
        pen_up_travel(&ordered, a.start),
        before,
        g.lines().count()
    );
    Ok(())
}

fn main() -> Result<()> {
    match Cli::parse().cmd {
        Cmd::Send {
            file,
            port,
            baud,
            status_hz,
        } => stream::send::run(&file, &port, baud, status_hz),
        Cmd::Ports => stream::send::list_ports(),
        Cmd::Text {
            text,
            size,
            font,
            output,
            out,
        } => {
            let l = text::layout(&text, size, &font)?;
            write_program(&l.strokes, &out, &output)
        }
        Cmd::Svg {
            file,
            tolerance,
            output,
            out,
        } => {
            let src = std::fs::read_to_string(&file)
                .with_context(|| format!("reading {}", file.display()))?;
            let strokes = svg_in::strokes_from_svg(&src, tolerance)?;
            write_program(&strokes, &out, &output)
        }
        Cmd::Preview {
            file,
            output,
            width,
        } => {
            let src = std::fs::read_to_string(&file)
                .with_context(|| format!("reading {}", file.display()))?;
            let moves = toolpath::parse(&src)?;
            let (pm, st) = preview::render(&moves, width)?;
            pm.save_png(&output)
                .with_context(|| format!("writing {}", output.display()))?;
            eprintln!(
                "{}: {}x{}, pen-down {:.1} mm, pen-up {:.1} mm",
                output.display(),
                pm.width(),
                pm.height(),
                st.draw_mm,
                st.travel_mm
            );
            Ok(())
        }
        Cmd::PlanBench { text, vpype, kicks } => {
            let mut opts = PlanOptions::default();
            opts.effort.kicks = kicks;
            let rows = bench::run(&text, &opts, (!vpype.is_empty()).then_some(vpype.as_str()))?;
            println!("text: {text}  (units: 1/1024 of the character box; start: top-left of the first box)");
            print!("{}", bench::table(&rows));
            Ok(())
        }
    }
}
