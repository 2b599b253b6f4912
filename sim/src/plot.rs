//! PNG plots: path speed and per-axis acceleration versus time from a trace, and the
//! side-by-side comparison of acceleration profiles.
//!
//! Owns only layout and drawing (plotters, bitmap backend, with a bundled font so that
//! text renders on a machine without system fonts). The numbers come from
//! [`crate::kinematics`] and [`crate::profiles`].

use crate::kinematics::Kinematics;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Registers the bundled DejaVu Sans as plotters' "sans-serif".
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .map_err(|_| ())
            .expect("bundled font is valid");
    });
}

const AXIS_COLOURS: [RGBColor; 3] = [
    RGBColor(200, 40, 40),
    RGBColor(30, 120, 30),
    RGBColor(40, 60, 200),
];
const AXIS_NAMES: [&str; 3] = ["X", "Y", "Z"];

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals.fold((0.0f64, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let pad = ((hi - lo) * 0.08).max(1e-9);
    (lo - pad, hi + pad)
}

type Err = String;
fn e<T: std::fmt::Debug>(x: T) -> Err {
    format!("plot: {x:?}")
}

/// Speed and acceleration from a trace, two panels, `title` on top.
pub fn trace_plot(k: &Kinematics, title: &str, out: &Path) -> Result<(), Err> {
    register_font();
    let root = BitMapBackend::new(out, (1100, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let root = root.titled(title, ("sans-serif", 24)).map_err(e)?;
    let panels = root.split_evenly((2, 1));
    let t_end = k.t_s.last().copied().unwrap_or(1.0).max(1e-6);

    let (lo, hi) = range(k.speed.iter().copied());
    let mut c = ChartBuilder::on(&panels[0])
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .caption("path speed (XY)", ("sans-serif", 18))
        .build_cartesian_2d(0.0..t_end, lo..hi)
        .map_err(e)?;
    c.configure_mesh()
        .x_desc("time (s)")
        .y_desc("mm/s")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(e)?;
    c.draw_series(LineSeries::new(
        k.t_s.iter().copied().zip(k.speed.iter().copied()),
        BLACK.stroke_width(2),
    ))
    .map_err(e)?;

    let moving: Vec<usize> = (0..3)
        .filter(|&a| k.vel[a].iter().any(|&v| v != 0.0))
        .collect();
    let (lo, hi) = range(moving.iter().flat_map(|&a| k.acc[a].iter().copied()));
    let mut c = ChartBuilder::on(&panels[1])
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .caption("acceleration per axis", ("sans-serif", 18))
        .build_cartesian_2d(0.0..t_end, lo..hi)
        .map_err(e)?;
    c.configure_mesh()
        .x_desc("time (s)")
        .y_desc("mm/s²")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(e)?;
    for &a in &moving {
        let col = AXIS_COLOURS[a];
        c.draw_series(LineSeries::new(
            k.t_s.iter().copied().zip(k.acc[a].iter().copied()),
            col.stroke_width(1),
        ))
        .map_err(e)?
        .label(AXIS_NAMES[a])
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(3)));
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// One named curve set of a profile: time (s) and velocity, acceleration, position.
pub struct ProfileCurves {
    pub name: String,
    pub t: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub x: Vec<f64>,
}

/// The profiles side by side: one column per profile, rows velocity, acceleration,
/// position, with shared scales so they compare at a glance. Accelerations beyond
/// `a_clip` (the impulses of a speed jump) are drawn clipped at the chart's edge.
pub fn profiles_plot(
    profiles: &[ProfileCurves],
    units: [&str; 3],
    t_label: &str,
    a_clip: f64,
    title: &str,
    out: &Path,
) -> Result<(), Err> {
    register_font();
    let cols = profiles.len().max(1);
    let root = BitMapBackend::new(out, (360 * cols as u32 + 40, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let root = root.titled(title, ("sans-serif", 24)).map_err(e)?;
    let cells = root.split_evenly((3, cols));
    let t_end = profiles
        .iter()
        .flat_map(|p| p.t.last().copied())
        .fold(0.0, f64::max)
        .max(1e-9);
    let ranges = [
        range(profiles.iter().flat_map(|p| p.v.iter().copied())),
        range(
            profiles
                .iter()
                .flat_map(|p| p.a.iter().map(|a| a.clamp(-a_clip, a_clip))),
        ),
        range(profiles.iter().flat_map(|p| p.x.iter().copied())),
    ];
    let names = ["velocity", "acceleration", "position"];
    let colours = [
        RGBColor(30, 120, 30),
        RGBColor(200, 40, 40),
        RGBColor(40, 60, 200),
    ];
    for (col, p) in profiles.iter().enumerate() {
        for row in 0..3 {
            let clipped: Vec<f64> = p.a.iter().map(|a| a.clamp(-a_clip, a_clip)).collect();
            let ys = [&p.v, &clipped, &p.x][row];
            let (lo, hi) = ranges[row];
            let caption = if row == 0 {
                format!("{}: {}", p.name, names[row])
            } else {
                names[row].to_string()
            };
            let mut c = ChartBuilder::on(&cells[row * cols + col])
                .margin(10)
                .x_label_area_size(34)
                .y_label_area_size(62)
                .caption(caption, ("sans-serif", 16))
                .build_cartesian_2d(0.0..t_end, lo..hi)
                .map_err(e)?;
            c.configure_mesh()
                .x_desc(t_label)
                .y_desc(units[row])
                .x_labels(5)
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(e)?;
            c.draw_series(LineSeries::new(
                p.t.iter().copied().zip(ys.iter().copied()),
                colours[row].stroke_width(2),
            ))
            .map_err(e)?;
        }
    }
    root.present().map_err(e)?;
    Ok(())
}
