//! The `cargo host` command line: argument parsing and glue only; the work
//! is done by the library modules.
use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use inkstep_host::gcode_out::{to_gcode, GcodeOptions, Pen};
use inkstep_host::geom::{pen_up_travel, Pt, Route, Stroke};
use inkstep_host::plan::{plan, PlanOptions};
use inkstep_host::{bench, preview, stream, svg_in, text, toolpath, web};
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
    /// A web page for the machine (PC or phone): the drawing live, state,
    /// controls, settings, and jobs from G-code, SVG or text.
    Serve {
        /// Serial port, e.g. /dev/ttyACM0 or the simulator's pty.
        #[arg(long)]
        port: String,
        /// Address to listen on. On a loopback address the page is open; on
        /// any other, controlling needs the token printed at start.
        #[arg(long, default_value = "127.0.0.1:8080")]
        listen: std::net::SocketAddr,
        /// Without the token, show nothing (instead of a page to watch).
        #[arg(long)]
        private: bool,
        /// A host name the page may also be reached by (e.g. plotter.local);
        /// requests naming any other host are refused. Repeatable.
        #[arg(long = "allow-host", value_name = "NAME")]
        allow_host: Vec<String>,
    },
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
    /// Pen-up travel of the driven route (read back from the G-code, park
    /// included) for natural, greedy, inkstep and vpype orders; fails when
    /// vpype ran and inkstep misses the goal (<= 0.85 x vpype's best).
    PlanBench {
        /// Texts to measure (default: the three benchmark texts).
        texts: Vec<String>,
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
    /// Pen start position "X,Y" in mm (where the planned route begins).
    #[arg(long, default_value = "0,0", value_parser = parse_pt, allow_hyphen_values = true)]
    start: Pt,
    /// Where the job parks the pen: "origin", "none" (it stays after the last
    /// stroke) or "X,Y" in mm. The planner optimises the route up to there.
    #[arg(long, default_value = "origin", value_parser = parse_park, allow_hyphen_values = true)]
    park: Park,
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

/// The `--park` choice.
#[derive(Clone, Copy, Debug)]
struct Park(Option<Pt>);

fn parse_park(s: &str) -> Result<Park, String> {
    match s {
        "origin" => Ok(Park(Some(Pt::new(0.0, 0.0)))),
        "none" => Ok(Park(None)),
        _ => parse_pt(s).map(|p| Park(Some(p))),
    }
}

fn parse_pt(s: &str) -> Result<Pt, String> {
    let (x, y) = s.split_once(',').ok_or("expected X,Y")?;
    Ok(Pt::new(
        x.trim().parse().map_err(|_| "bad X")?,
        y.trim().parse().map_err(|_| "bad Y")?,
    ))
}

fn write_program(strokes: &[Stroke], a: &OutArgs, output: &PathBuf) -> Result<()> {
    let route = Route {
        start: a.start,
        park: a.park.0,
    };
    let before = pen_up_travel(strokes, route);
    let ordered = if a.no_plan {
        strokes.to_vec()
    } else {
        let opts = PlanOptions {
            reverse: !a.keep_direction,
            join: !a.no_join,
            ..PlanOptions::default()
        };
        plan(strokes, route, &opts)
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
        route,
    };
    let g = to_gcode(&ordered, &o);
    std::fs::write(output, &g).with_context(|| format!("writing {}", output.display()))?;
    eprintln!(
        "{}: {} strokes in, {} out; pen-up travel {:.1} mm with the park (as given {:.1} mm); {} lines",
        output.display(),
        strokes.len(),
        ordered.len(),
        pen_up_travel(&ordered, route),
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
        Cmd::Serve {
            port,
            listen,
            private,
            allow_host,
        } => web::run(port, listen, private, allow_host),
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
        Cmd::PlanBench {
            texts,
            vpype,
            kicks,
        } => {
            let mut opts = PlanOptions::default();
            opts.effort.kicks = kicks;
            let texts = if texts.is_empty() {
                bench::TEXTS.iter().map(|t| t.to_string()).collect()
            } else {
                texts
            };
            let mut missed = Vec::new();
            for text in &texts {
                let r = bench::run(text, &opts, (!vpype.is_empty()).then_some(vpype.as_str()))?;
                println!(
                    "\ntext: {text}  ({} mm boxes; pen starts at the origin and parks there)",
                    bench::SIZE_MM
                );
                print!("{}", bench::table(&r));
                if let Some(ratio) = r.ratio() {
                    let ok = ratio <= bench::GOAL;
                    println!(
                        "inkstep / vpype best = {ratio:.3} (goal <= {}): {}",
                        bench::GOAL,
                        if ok { "met" } else { "MISSED" }
                    );
                    if !ok {
                        missed.push(text.clone());
                    }
                }
            }
            if !missed.is_empty() {
                anyhow::bail!("goal missed on: {}", missed.join(", "));
            }
            Ok(())
        }
    }
}
