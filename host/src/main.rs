//! The `cargo host` command line: argument parsing and glue only; the work
//! is done by the library modules.
use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use inkstep_host::biarc::ArcHints;
use inkstep_host::gcode_out::{check_coords, to_gcode_passes, GcodeOptions, Pass, Pen};
use inkstep_host::geom::{bounds, pen_up_travel, Pt, Route, Stroke};
use inkstep_host::plan::{plan, PlanOptions};
use inkstep_host::svg_in::{self as svg, LayerMode, SkipKind, SvgOptions};
use inkstep_host::{bench, preview, stream, text, toolpath, web};
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
        /// Resume at this line of the file (1-based): the state before it
        /// (units, modes, offsets, feed, pen) is rebuilt, the pen travels up
        /// to where the line starts, and the job goes on.
        #[arg(long, value_name = "N", conflicts_with = "resume")]
        from_line: Option<usize>,
        /// Resume where the last run of this file stopped (remembered in the
        /// user's cache folder, inkstep/resume.tsv).
        #[arg(long)]
        resume: bool,
    },
    /// The job time from the firmware's own planner (the program run on a
    /// virtual board), pen lifts and drops included, with the board's settings
    /// (read from --port with $$, or from --settings / --set, else the
    /// firmware's defaults).
    Estimate {
        file: PathBuf,
        #[command(flatten)]
        machine: MachineArgs,
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
    /// SVG (or SVGZ) to G-code: paths and shapes, transforms applied, curves
    /// flattened; layers as passes with pen changes; what cannot be drawn is
    /// named on stderr.
    Svg {
        file: PathBuf,
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        svg: SvgArgs,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Render G-code to PNG: pen-down strokes blue, pen-up travel red dashed.
    /// Given an SVG, it shows what `svg` would draw and, in orange, what it
    /// leaves out (text, images, fills not hatched), on the page outline (grey)
    /// and the machine travel (dashed).
    Preview {
        file: PathBuf,
        #[command(flatten)]
        svg: SvgArgs,
        #[arg(short, long)]
        output: PathBuf,
        /// Image width in pixels.
        #[arg(long, default_value_t = 1600)]
        width: u32,
        #[command(flatten)]
        machine: MachineArgs,
    },
    /// A generated drawing of N paths (179,000 make 20 MB of SVG) from SVG text
    /// to G-code: the time of each stage; fails above a minute in all.
    SvgBench {
        #[arg(long, default_value_t = 179_000)]
        paths: usize,
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

#[derive(Clone, Copy, ValueEnum, PartialEq)]
enum Passes {
    /// Inkscape layers (top-level `inkscape:groupmode="layer"` groups).
    Layers,
    /// One pass per stroke colour.
    ByColor,
    /// One pass.
    None,
}

#[derive(Clone, Copy, ValueEnum, PartialEq)]
enum Fill {
    /// Filled shapes are drawn as outlines (and named on stderr).
    None,
    /// Filled shapes are hatched (and outlined).
    Hatch,
}

/// How an SVG is read.
#[derive(Args)]
struct SvgArgs {
    /// Largest distance of a curve from its flattened polyline (mm).
    #[arg(long, default_value_t = 0.05)]
    tolerance: f64,
    /// Passes: Inkscape layers, stroke colours, or one pass. Several passes
    /// get a pen change (M6 T<n> and a message naming the layer) between them.
    #[arg(long, value_enum, default_value = "layers")]
    layers: Passes,
    #[arg(long, value_enum, default_value = "none")]
    fill: Fill,
    /// Distance between hatch lines (mm).
    #[arg(long, default_value_t = 0.5)]
    hatch_spacing: f64,
    /// Angle of the hatch lines (degrees, counter-clockwise from X).
    #[arg(long, default_value_t = 45.0, allow_negative_numbers = true)]
    hatch_angle: f64,
    /// Draw <text> with this Hershey font (futural, scripts, cursive,
    /// futuram) instead of leaving it out.
    #[arg(long)]
    text_font: Option<String>,
    /// Machine travel "W,H" in mm ($130,$131; the firmware's defaults).
    #[arg(long, default_value = "300,200", value_parser = parse_pt)]
    travel: Pt,
    /// Scale (keeping proportions) and move the drawing to fill the machine
    /// travel less a margin (mm).
    #[arg(long)]
    fit: Option<f64>,
    /// Scale the drawing about the origin by this factor.
    #[arg(long)]
    scale: Option<f64>,
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
    /// Send curves as arcs (G2/G3) where the points lie on a circle within
    /// this tolerance (mm; 0.01 when given without a value).
    #[arg(long, num_args = 0..=1, default_missing_value = "0.01")]
    arcs: Option<f64>,
}

/// Where the machine's settings come from (for the time estimate).
#[derive(Args)]
struct MachineArgs {
    /// Read the settings from the board on this port ($$).
    #[arg(long = "port")]
    settings_port: Option<String>,
    #[arg(long, default_value_t = 115200)]
    baud: u32,
    /// A file of `$N=V` lines (e.g. the board's `$$` listing).
    #[arg(long)]
    settings: Option<PathBuf>,
    /// A setting, `N=V` (e.g. --set 110=5000); repeatable, applied last.
    #[arg(long = "set", value_name = "N=V")]
    set: Vec<String>,
}

fn machine_settings(m: &MachineArgs) -> Result<inkstep_core::settings::Settings> {
    let mut s = if let Some(p) = &m.settings_port {
        let mut t =
            inkstep_serial::port::Port::open(p, m.baud).with_context(|| format!("opening {p}"))?;
        inkstep_host::estimate::read_settings(&mut t)?
    } else if let Some(f) = &m.settings {
        let text =
            std::fs::read_to_string(f).with_context(|| format!("reading {}", f.display()))?;
        inkstep_host::estimate::settings_from_text(&text)
            .with_context(|| format!("reading {}", f.display()))?
    } else {
        inkstep_core::settings::Settings::default()
    };
    inkstep_host::estimate::apply_flags(&mut s, &m.set)?;
    Ok(s)
}

/// Prints the estimate of `program` on stdout, warnings on stderr.
fn print_estimate(name: &str, program: &str, s: &inkstep_core::settings::Settings) {
    let e = inkstep_host::estimate::estimate(program, s, Pt::new(0.0, 0.0), &[]);
    for w in e.warnings() {
        eprintln!("warning: {w}");
    }
    println!(
        "{name}: estimated job time {} ({:.3} s), the firmware's planner with the machine's settings",
        inkstep_host::estimate::fmt_time(e.job_s),
        e.job_s
    );
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

fn gcode_options(a: &OutArgs, route: Route) -> Result<GcodeOptions> {
    if let Some(t) = a.arcs {
        if !(t > 0.0 && t <= 10.0) {
            anyhow::bail!("--arcs tolerance must be in (0, 10] mm");
        }
    }
    let pen = match a.pen {
        PenMode::M3 => Pen::M3,
        PenMode::Z => Pen::Z {
            up: a.z_up,
            down: a.z_down,
            feed: a.z_feed,
        },
    };
    Ok(GcodeOptions {
        pen,
        feed: a.feed,
        dwell: a.dwell,
        route,
        arcs: a.arcs,
        arc_hints: ArcHints::default(),
    })
}

/// Plans each pass (from where the last one ended; the last one up to the
/// park) and writes the program.
fn write_program(
    passes: &[Pass],
    a: &OutArgs,
    arc_hints: ArcHints,
    output: &PathBuf,
) -> Result<()> {
    let route = Route {
        start: a.start,
        park: a.park.0,
    };
    let o = GcodeOptions {
        arc_hints,
        ..gcode_options(a, route)?
    };
    let all: Vec<Stroke> = passes
        .iter()
        .flat_map(|p| p.strokes.iter().cloned())
        .collect();
    check_coords(&all, &o)?;
    let before = pen_up_travel(&all, route);
    let mut at = a.start;
    let mut planned = Vec::new();
    for (k, p) in passes.iter().enumerate() {
        let last = k + 1 == passes.len();
        let r = Route {
            start: at,
            park: if last { a.park.0 } else { None },
        };
        let ordered = if a.no_plan {
            p.strokes.clone()
        } else {
            let opts = PlanOptions {
                reverse: !a.keep_direction,
                join: !a.no_join,
                progress: true,
                ..PlanOptions::default()
            };
            plan(&p.strokes, r, &opts)
        };
        if let Some(e) = ordered.iter().rev().find_map(|s| s.last()) {
            at = *e;
        }
        planned.push(Pass {
            name: p.name.clone(),
            strokes: ordered,
        });
    }
    let g = to_gcode_passes(&planned, &o);
    std::fs::write(output, &g).with_context(|| format!("writing {}", output.display()))?;
    let out: Vec<Stroke> = planned
        .iter()
        .flat_map(|p| p.strokes.iter().cloned())
        .collect();
    eprintln!(
        "{}: {} strokes in, {} out; pen-up travel {:.1} mm with the park (as given {:.1} mm); {} lines",
        output.display(),
        all.len(),
        out.len(),
        pen_up_travel(&out, route),
        before,
        g.lines().count()
    );
    if planned.len() > 1 {
        eprintln!(
            "{} passes with a pen change (M6 T<n>) before each after the first: {}. \
             The board lifts the pen and waits for cycle start (~ or key D) at each; \
             --layers none draws one pass.",
            planned.len(),
            planned
                .iter()
                .map(|p| format!("\"{}\"", p.name))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(())
}

/// Reads an SVG as `svg` does: scaled or fitted as asked, what is left out
/// named and the travel checked on stderr. Fails when nothing is drawable.
fn load_svg(file: &PathBuf, a: &SvgArgs, arcs: Option<f64>) -> Result<svg::Drawing> {
    let data = std::fs::read(file).with_context(|| format!("reading {}", file.display()))?;
    let opt = SvgOptions {
        tol_mm: a.tolerance,
        layers: match a.layers {
            Passes::Layers => LayerMode::Layers,
            Passes::ByColor => LayerMode::ByColor,
            Passes::None => LayerMode::None,
        },
        hatch: (a.fill == Fill::Hatch).then_some((a.hatch_spacing, a.hatch_angle)),
        text_font: a.text_font.clone(),
        arcs,
    };
    let mut d =
        svg::read_svg(&data, &opt).with_context(|| format!("reading {}", file.display()))?;
    for kind in [SkipKind::Text, SkipKind::Image, SkipKind::Fill] {
        let names: Vec<&str> = d
            .skipped
            .iter()
            .filter(|s| s.kind == kind)
            .map(|s| s.name.as_str())
            .collect();
        if names.is_empty() {
            continue;
        }
        let shown = names.iter().take(8).cloned().collect::<Vec<_>>().join(", ");
        let more = if names.len() > 8 {
            format!(" and {} more", names.len() - 8)
        } else {
            String::new()
        };
        let hint = match kind {
            SkipKind::Text => "not drawn (convert it with Object to Path, or --text-font futural)",
            SkipKind::Image => "not drawn (a pen cannot draw pixels)",
            SkipKind::Fill => "outline drawn, inside not filled (--fill hatch fills it)",
        };
        eprintln!("{} {}: {shown}{more}: {hint}", names.len(), kind.label());
    }
    let strokes = d.strokes();
    if strokes.is_empty() {
        anyhow::bail!(
            "nothing drawable in {}{}",
            file.display(),
            if d.skipped.is_empty() {
                " (no visible paths or shapes)"
            } else {
                " (only what is listed above)"
            }
        );
    }
    let Some((lo, hi)) = bounds(&strokes) else {
        anyhow::bail!("nothing drawable in {}", file.display());
    };
    let (tw, th) = (a.travel.x, a.travel.y);
    if !(tw > 0.0 && th > 0.0) {
        anyhow::bail!("--travel must be two positive sizes in mm");
    }
    let scale_move = |d: &mut svg::Drawing, k: f64, off: Pt| {
        let f = |p: &mut Pt| *p = Pt::new(p.x * k + off.x, p.y * k + off.y);
        d.layers
            .iter_mut()
            .flat_map(|l| l.strokes.iter_mut())
            .flatten()
            .for_each(f);
        d.skipped
            .iter_mut()
            .flat_map(|s| s.outline.iter_mut().flatten())
            .for_each(f);
        d.arc_hints.scale_move(k, off);
    };
    if let Some(k) = a.scale {
        if !(k > 0.0 && k.is_finite()) {
            anyhow::bail!("--scale must be a positive factor");
        }
        scale_move(&mut d, k, Pt::new(0.0, 0.0));
        d.page = (d.page.0 * k, d.page.1 * k);
    }
    if let Some(m) = a.fit {
        let (lo, hi) = bounds(&d.strokes()).unwrap_or((lo, hi));
        let (w, h) = ((hi.x - lo.x).max(1e-9), (hi.y - lo.y).max(1e-9));
        let k = ((tw - 2.0 * m) / w).min((th - 2.0 * m) / h);
        if !(k > 0.0 && m >= 0.0) {
            anyhow::bail!("--fit margin {m} mm leaves no room in the travel {tw} x {th} mm");
        }
        scale_move(&mut d, k, Pt::new(m - lo.x * k, m - lo.y * k));
        eprintln!("fitted: scaled by {k:.4} into {tw} x {th} mm less {m} mm margins");
    }
    let (lo, hi) = bounds(&d.strokes()).unwrap_or((lo, hi));
    let eps = 1e-6;
    if lo.x < -eps || lo.y < -eps || hi.x > tw + eps || hi.y > th + eps {
        eprintln!(
            "warning: the drawing spans X {:.1}..{:.1}, Y {:.1}..{:.1} mm, outside the machine \
             travel 0..{tw} x 0..{th} mm ($130/$131; --travel W,H): --fit MARGIN scales it to fit",
            lo.x, hi.x, lo.y, hi.y
        );
    }
    if a.scale.is_none()
        && a.fit.is_none()
        && (lo.x < -0.01 || lo.y < -0.01 || hi.x > d.page.0 + 0.01 || hi.y > d.page.1 + 0.01)
    {
        eprintln!(
            "warning: parts of the drawing lie off the page ({:.1} x {:.1} mm)",
            d.page.0, d.page.1
        );
    }
    Ok(d)
}

fn main() -> Result<()> {
    match Cli::parse().cmd {
        Cmd::Send {
            file,
            port,
            baud,
            status_hz,
            from_line,
            resume,
        } => stream::send::run(&stream::send::SendOptions {
            file: &file,
            port: &port,
            baud,
            status_hz,
            from: match (from_line, resume) {
                (Some(n), _) => stream::send::From::Line(n),
                (None, true) => stream::send::From::Remembered,
                (None, false) => stream::send::From::Start,
            },
        }),
        Cmd::Estimate { file, machine } => {
            let program = std::fs::read_to_string(&file)
                .with_context(|| format!("reading {}", file.display()))?;
            inkstep_serial::stream::prepare(&program, 128).map_err(anyhow::Error::msg)?;
            let s = machine_settings(&machine)?;
            print_estimate(&file.display().to_string(), &program, &s);
            Ok(())
        }
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
            let pass = Pass {
                name: String::new(),
                strokes: l.strokes,
            };
            write_program(&[pass], &out, ArcHints::default(), &output)
        }
        Cmd::Svg {
            file,
            output,
            svg,
            out,
        } => {
            let d = load_svg(&file, &svg, out.arcs)?;
            let hints = d.arc_hints;
            let passes: Vec<Pass> = d
                .layers
                .into_iter()
                .map(|l| Pass {
                    name: l.name,
                    strokes: l.strokes,
                })
                .collect();
            write_program(&passes, &out, hints, &output)
        }
        Cmd::Preview {
            file,
            svg,
            output,
            width,
            machine,
        } => {
            let settings = machine_settings(&machine)?;
            let is_svg = std::fs::read(&file)
                .map(|b| {
                    b.starts_with(&[0x1f, 0x8b])
                        || String::from_utf8_lossy(&b[..b.len().min(4096)]).contains("<svg")
                })
                .unwrap_or(false);
            let (moves, extra, program) = if is_svg {
                let d = load_svg(&file, &svg, None)?;
                let o = GcodeOptions::default();
                let passes: Vec<Pass> = d
                    .layers
                    .iter()
                    .map(|l| Pass {
                        name: l.name.clone(),
                        strokes: l.strokes.clone(),
                    })
                    .collect();
                let g = to_gcode_passes(&passes, &o);
                let extra = preview::Extra {
                    left_out: d.skipped.iter().map(|s| s.outline.clone()).collect(),
                    page: Some(d.page),
                    travel: Some((svg.travel.x, svg.travel.y)),
                };
                (toolpath::parse(&g)?, extra, g)
            } else {
                let src = std::fs::read_to_string(&file)
                    .with_context(|| format!("reading {}", file.display()))?;
                (toolpath::parse(&src)?, preview::Extra::default(), src)
            };
            let (pm, st) = preview::render_with(&moves, &extra, width)?;
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
            if is_svg {
                eprintln!(
                    "blue: drawn; red dashed: pen-up travel; grey: the page; grey dashed: the \
                     machine travel; orange: left out ({} items) and drawn parts outside the travel",
                    extra.left_out.len()
                );
            }
            print_estimate(&file.display().to_string(), &program, &settings);
            Ok(())
        }
        Cmd::SvgBench { paths } => {
            let f = inkstep_host::svg_bench::run(paths, true)?;
            println!(
                "{} paths, {:.1} MB of SVG: read {:.1} s, plan {:.1} s, write {:.1} s, total {:.1} s \
                 (goal < {} s); {} G-code lines; pen-up travel {:.0} mm planned, {:.0} mm as drawn",
                f.paths,
                f.bytes as f64 / 1e6,
                f.read_s,
                f.plan_s,
                f.write_s,
                f.total_s(),
                inkstep_host::svg_bench::GOAL_S,
                f.lines,
                f.travel_after,
                f.travel_before
            );
            if f.total_s() > inkstep_host::svg_bench::GOAL_S {
                anyhow::bail!("goal missed: {:.1} s", f.total_s());
            }
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
