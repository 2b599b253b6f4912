//! `cargo host svg` and `cargo host preview` on the inputs users bring: layers
//! become passes with pen changes, nothing drawable fails, broken sizes are
//! refused or warned about, arcs replay the same drawing, every line fits the
//! board's buffer, and no input (random or hostile) makes the tool panic.

use inkstep_core::gcode::LINE_MAX;
use inkstep_host::gcode_out::{to_gcode_passes, GcodeOptions, Pass};
use inkstep_host::geom::{Pt, Route};
use inkstep_host::plan::{plan, Effort, PlanOptions};
use inkstep_host::svg_in::{read_svg, LayerMode, SvgOptions};
use inkstep_host::toolpath::{check_grbl, parse, MoveKind};
use proptest::prelude::*;
use std::path::PathBuf;
use std::process::{Command, Output};
use std::time::Duration;

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("inkstep-svgcli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn write(name: &str, body: &str) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, body).unwrap();
    p
}

fn page(body: &str) -> String {
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"
             width="100mm" height="100mm" viewBox="0 0 100 100">{body}</svg>"#
    )
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn svg_to_gcode(svg: &std::path::Path, extra: &[&str]) -> (Output, String) {
    let g = svg.with_extension("gcode");
    let _ = std::fs::remove_file(&g);
    let mut args = vec!["svg", svg.to_str().unwrap(), "-o", g.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = run(&args);
    let text = std::fs::read_to_string(&g).unwrap_or_default();
    (o, text)
}

#[test]
fn layers_are_passes_with_a_pen_change_between() {
    let svg = write(
        "layers.svg",
        &page(
            r##"<g inkscape:groupmode="layer" id="l1" inkscape:label="Fine black">
                  <path d="M 10 10 H 40" stroke="#000"/></g>
                <g inkscape:groupmode="layer" id="l2" inkscape:label="Red (thick)">
                  <path d="M 10 20 H 40" stroke="#f00"/><path d="M 10 30 H 40" stroke="#f00"/></g>"##,
        ),
    );
    let (o, g) = svg_to_gcode(&svg, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    check_grbl(&g).unwrap();
    let lines: Vec<&str> = g.lines().collect();
    let m6: Vec<usize> = (0..lines.len()).filter(|&k| lines[k] == "M6 T2").collect();
    assert_eq!(m6.len(), 1, "{g}");
    // The pen is up at the change, the message names the layer (parentheses
    // could end the comment early, so they are replaced).
    let k = m6[0];
    assert_eq!(lines[k - 1], "(MSG,pen 2: Red _thick_)");
    assert_eq!(lines[k - 2], "M5");
    // Everything of layer 1 is drawn before the change, all of layer 2 after.
    let moves = parse(&g).unwrap();
    let drawn_y = |from: usize, to: usize| -> Vec<f64> {
        moves
            .iter()
            .filter(|m| m.kind == MoveKind::Draw && m.line > from && m.line <= to)
            .map(|m| m.to.y)
            .collect()
    };
    assert!(drawn_y(0, k).iter().all(|&y| (y - 90.0).abs() < 1e-3));
    let after = drawn_y(k, lines.len());
    assert!(
        after.iter().any(|&y| (y - 80.0).abs() < 1e-3)
            && after.iter().any(|&y| (y - 70.0).abs() < 1e-3)
    );
    assert!(after.iter().all(|&y| (y - 90.0).abs() > 1.0));
    assert!(
        stderr(&o).contains("M6"),
        "the firmware's missing M6 is said"
    );
    // One pass: no pen change at all.
    let (o, g) = svg_to_gcode(&svg, &["--layers", "none"]);
    assert!(o.status.success());
    assert!(!g.contains("M6") && !g.contains("MSG"), "{g}");
    // By colour: black, then red.
    let (_, g) = svg_to_gcode(&svg, &["--layers", "by-color"]);
    assert!(g.contains("(MSG,pen 1: #000000)") && g.contains("(MSG,pen 2: #ff0000)"));
}

#[test]
fn nothing_drawable_fails_and_says_why() {
    let svg = write(
        "empty.svg",
        &page(
            r#"<text id="t1" x="10" y="10">Hello</text><line x1="5" y1="5" x2="5" y2="5" stroke="black"/>"#,
        ),
    );
    let (o, g) = svg_to_gcode(&svg, &[]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("nothing drawable") && e.contains("t1 \"Hello\""),
        "{e}"
    );
    assert!(g.is_empty(), "no program is written");
    // With a Hershey font the text is drawn.
    let (o, g) = svg_to_gcode(&svg, &["--text-font", "futural"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(parse(&g).unwrap().iter().any(|m| m.kind == MoveKind::Draw));
    // Not an SVG at all.
    let bad = write("bad.svg", "\u{feff}not xml <<<");
    let (o, _) = svg_to_gcode(&bad, &[]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("parsing SVG"), "{}", stderr(&o));
}

#[test]
fn huge_drawings_are_refused_or_warned_and_lines_stay_short() {
    // 1e17 px: refused with the element's name, no panic.
    let svg = write(
        "huge.svg",
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="100" height="100">
             <path id="wild" d="M 1e17 1e17 L -1e17 5" stroke="black"/></svg>"#,
    );
    for extra in [&[][..], &["--no-join"][..]] {
        let (o, g) = svg_to_gcode(&svg, extra);
        assert!(!o.status.success());
        assert!(stderr(&o).contains("wild"), "{}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
        assert!(g.is_empty());
    }
    // 90 m: accepted, every line within the board's limit, and a warning
    // that it leaves the travel; --fit brings it in.
    let svg = write(
        "big.svg",
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="100m" height="100m" viewBox="0 0 100000 100000">
             <path d="M -89999.9999 -89999.9999 C 1 2 3 4 89999.1234 -89999.9876" stroke="black"/></svg>"#,
    );
    let (o, g) = svg_to_gcode(&svg, &["--no-join", "--arcs"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("outside the machine travel"),
        "{}",
        stderr(&o)
    );
    assert!(g.lines().all(|l| l.len() <= LINE_MAX));
    check_grbl(&g).unwrap();
    let (o, g) = svg_to_gcode(&svg, &["--fit", "10"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("outside the machine travel"),
        "{}",
        stderr(&o)
    );
    for m in parse(&g)
        .unwrap()
        .iter()
        .filter(|m| m.kind == MoveKind::Draw)
    {
        assert!(
            m.to.x >= 10.0 - 1e-3
                && m.to.x <= 290.0 + 1e-3
                && m.to.y >= 10.0 - 1e-3
                && m.to.y <= 190.0 + 1e-3
        );
    }
}

#[test]
fn arcs_draw_the_same_picture_in_fewer_lines() {
    let svg = write(
        "circles.svg",
        &page(
            r#"<circle cx="30" cy="30" r="20" fill="none" stroke="black"/>
               <ellipse cx="60" cy="60" rx="30" ry="10" fill="none" stroke="black"/>
               <path d="M 10 90 C 30 60 50 100 90 80" fill="none" stroke="black"/>
               <rect x="70" y="10" width="20" height="20" rx="4" fill="none" stroke="black"/>"#,
        ),
    );
    let (o1, flat) = svg_to_gcode(&svg, &[]);
    let (o2, arcs) = svg_to_gcode(&svg, &["--arcs", "0.01"]);
    assert!(o1.status.success() && o2.status.success());
    check_grbl(&arcs).unwrap();
    assert!(arcs.contains("G2 ") || arcs.contains("G3 "));
    assert!(
        arcs.lines().count() * 3 < flat.lines().count(),
        "{} vs {}",
        arcs.lines().count(),
        flat.lines().count()
    );
    // Every point the arcs program draws lies within 0.06 mm of the flattened
    // drawing (0.01 at the fitted points, the 0.05 flattening between), and
    // the lengths agree within 0.1 %.
    let draw = |g: &str| -> Vec<(Pt, Pt)> {
        parse(g)
            .unwrap()
            .into_iter()
            .filter(|m| m.kind == MoveKind::Draw)
            .map(|m| (m.from, m.to))
            .collect()
    };
    let (a, f) = (draw(&arcs), draw(&flat));
    let len = |v: &[(Pt, Pt)]| v.iter().map(|s| s.0.dist(s.1)).sum::<f64>();
    assert!(
        (len(&a) - len(&f)).abs() / len(&f) < 1e-3,
        "{} {}",
        len(&a),
        len(&f)
    );
    for (p, _) in &a {
        let d = f
            .iter()
            .map(|&(s, e)| inkstep_host::svg_in::dist_to_segment(*p, s, e))
            .fold(f64::INFINITY, f64::min);
        assert!(d < 0.06, "{p:?} is {d} mm off");
    }
}

#[test]
fn svg_preview_shows_the_page_and_what_is_left_out() {
    let svg = write(
        "pv.svg",
        &page(
            r#"<rect x="10" y="10" width="30" height="20" fill="none" stroke="black"/>
               <text id="label" x="50" y="80" font-size="10">LEFT OUT</text>"#,
        ),
    );
    let png = tmp("pv.png");
    let o = run(&[
        "preview",
        svg.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--width",
        "800",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("label \"LEFT OUT\""));
    let img = tiny_skia::Pixmap::load_png(&png).unwrap();
    // Travel 300 x 200 mm fills the width: 760 px for 300 mm from a 20 px
    // margin, y up from the bottom margin. The text's box starts at (50, 20) mm.
    let k = 760.0 / 300.0;
    let at = |x: f64, y: f64| {
        let px = (20.0 + x * k) as u32;
        let py = (img.height() as f64 - 20.0 - y * k) as u32;
        img.pixel(px, py).unwrap()
    };
    let inside_text = at(60.0, 22.0);
    assert!(
        inside_text.red() > inside_text.blue() + 40,
        "orange shading: {inside_text:?}"
    );
    // The page outline (100 mm wide) is grey at its top edge.
    let edge = at(50.0, 100.0);
    assert!(
        edge.red() < 220 && (edge.red() as i32 - edge.blue() as i32).abs() < 20,
        "{edge:?}"
    );
    // The drawn rectangle's bottom edge (y = 70 mm) is blue.
    let r = at(25.0, 70.0);
    assert!(r.blue() > r.red() + 40, "{r:?}");
}

/// SVG-ish documents: valid shapes with wild numbers and transforms, and
/// broken markup.
fn svgish() -> impl Strategy<Value = String> {
    let num = prop_oneof![
        -200.0f64..200.0,
        Just(0.0),
        Just(1e17),
        Just(-1e300),
        Just(1e-300),
        Just(f64::MAX),
    ];
    let tf = prop_oneof![
        Just(String::new()),
        num.clone()
            .prop_map(|a| format!(r#" transform="rotate({a})""#)),
        (num.clone(), num.clone())
            .prop_map(|(a, b)| format!(r#" transform="translate({a},{b}) scale({})""#, a / 7.0)),
        Just(r#" transform="matrix(0 0 0 0 0 0)""#.to_string()),
    ];
    let elem = prop_oneof![
        (num.clone(), num.clone(), num.clone(), tf.clone()).prop_map(|(a, b, c, t)| format!(
            r#"<circle cx="{a}" cy="{b}" r="{c}" stroke="black"{t}/>"#
        )),
        (
            num.clone(),
            num.clone(),
            num.clone(),
            num.clone(),
            tf.clone()
        )
            .prop_map(|(a, b, c, d, t)| format!(
                r#"<path d="M {a} {b} C {c} {d} {b} {a} {d} {c} Z m 1 1" fill="red"{t}/>"#
            )),
        (num.clone(), num.clone(), tf.clone())
            .prop_map(|(a, b, t)| format!(r##"<use href="#p" x="{a}" y="{b}"{t}/>"##)),
        (num.clone(), tf.clone())
            .prop_map(|(a, t)| format!(r#"<text x="{a}" y="5"{t}>Hi (x)</text>"#)),
        (num.clone(), num.clone()).prop_map(|(a, b)| format!(
            r#"<svg x="{a}" width="{b}" viewBox="0 0 {b} {a}"><line x2="5" stroke="black"/></svg>"#
        )),
        Just("<g><<".to_string()),
        Just(r#"<path d="M 0 0 L 0 0" stroke="black" stroke-linecap="round"/>"#.to_string()),
    ];
    proptest::collection::vec(elem, 0..6).prop_map(|v| {
        format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"><defs><path id="p" d="M 0 0 L 3 4" stroke="black"/></defs>{}</svg>"#,
            v.join("")
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn no_input_panics_and_every_line_fits(svg in svgish(), hatch in any::<bool>(), arcs in any::<bool>()) {
        let opt = SvgOptions {
            layers: LayerMode::ByColor,
            hatch: hatch.then_some((2.0, 30.0)),
            text_font: Some("futural".into()),
            ..SvgOptions::default()
        };
        // Errors are fine (and must be clear); panics are not.
        if let Ok(d) = read_svg(svg.as_bytes(), &opt) {
            let route = Route::closed(Pt::new(0.0, 0.0));
            let quick = PlanOptions {
                effort: Effort { kicks: 2, time_limit: Duration::from_millis(200), window: 4 },
                ..PlanOptions::default()
            };
            let passes: Vec<Pass> = d
                .layers
                .iter()
                .map(|l| Pass { name: l.name.clone(), strokes: plan(&l.strokes, route, &quick) })
                .collect();
            let o = GcodeOptions { route, arcs: arcs.then_some(0.01), ..GcodeOptions::default() };
            let g = to_gcode_passes(&passes, &o);
            for l in g.lines() {
                prop_assert!(l.len() <= LINE_MAX, "{l}");
            }
            prop_assert!(check_grbl(&g).is_ok(), "{:?}", check_grbl(&g));
        }
    }
}

#[test]
fn the_planner_takes_absurd_coordinates_without_panicking() {
    // Once "attempt to add with overflow" in the Euler join's grid.
    let far = 1e17 * 25.4 / 96.0;
    let strokes = vec![
        vec![Pt::new(far, far), Pt::new(-far, 5.0)],
        vec![Pt::new(-far, 5.0), Pt::new(far, -far)],
        vec![Pt::new(f64::MAX, 0.0), Pt::new(0.0, f64::MIN)],
        vec![Pt::new(f64::NAN, 1.0), Pt::new(2.0, f64::INFINITY)],
        vec![Pt::new(1.0, 1.0), Pt::new(2.0, 2.0)],
    ];
    for reverse in [true, false] {
        let p = plan(
            &strokes,
            Route::closed(Pt::new(0.0, 0.0)),
            &PlanOptions {
                reverse,
                ..PlanOptions::default()
            },
        );
        let n_in: usize = strokes.iter().map(|s| s.len()).sum();
        let n_out: usize = p.iter().map(|s| s.len()).sum();
        assert!(n_out >= n_in - 1, "no point lost: {n_in} -> {n_out}");
    }
}

#[test]
fn svgz_reads_and_off_page_parts_are_warned_about() {
    use std::io::Write;
    let svg = page(r#"<path d="M 90 50 H 130" stroke="black"/>"#);
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(svg.as_bytes()).unwrap();
    let p = tmp("off.svgz");
    std::fs::write(&p, gz.finish().unwrap()).unwrap();
    let (o, g) = svg_to_gcode(&p, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("off the page (100.0 x 100.0 mm)"), "{e}");
    assert!(!e.contains("outside the machine travel"), "{e}");
    let drawn: Vec<_> = parse(&g)
        .unwrap()
        .into_iter()
        .filter(|m| m.kind == MoveKind::Draw)
        .collect();
    assert_eq!(drawn.len(), 1);
    let xs = [drawn[0].from.x, drawn[0].to.x];
    assert!(xs.contains(&90.0) && xs.contains(&130.0), "{xs:?}");
    // The preview takes the SVGZ too.
    let png = tmp("off.png");
    let o = run(&["preview", p.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_hatched_disc_is_few_strokes_inside_the_disc() {
    let svg = write(
        "disc.svg",
        &page(r#"<circle cx="50" cy="50" r="25" fill="black"/>"#),
    );
    let (o, g) = svg_to_gcode(
        &svg,
        &[
            "--fill",
            "hatch",
            "--hatch-spacing",
            "1",
            "--hatch-angle",
            "30",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let moves = parse(&g).unwrap();
    let pen_downs = g.lines().filter(|l| *l == "M3").count();
    // The outline and the hatching: a handful of strokes, not 50.
    assert!(pen_downs <= 6, "{pen_downs} strokes");
    for m in moves.iter().filter(|m| m.kind == MoveKind::Draw) {
        assert!(m.to.dist(Pt::new(50.0, 50.0)) <= 25.0 + 0.01, "{:?}", m.to);
    }
    // Ink inside: about area / spacing = 1963 mm of hatch plus the outline.
    let ink: f64 = moves
        .iter()
        .filter(|m| m.kind == MoveKind::Draw)
        .map(|m| m.from.dist(m.to))
        .sum();
    let want = std::f64::consts::PI * 625.0 + std::f64::consts::TAU * 25.0;
    assert!((ink - want).abs() / want < 0.05, "{ink} vs {want}");
}

/// Real files from tests/data/svg-real, cut, spliced and with bytes changed.
fn mutated_real_file() -> impl Strategy<Value = Vec<u8>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/svg-real");
    let mut files: Vec<Vec<u8>> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "svg")
                .then(|| std::fs::read(p).ok())
                .flatten()
        })
        .collect();
    files.sort();
    let n = files.len();
    (
        0..n,
        proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..8),
        any::<prop::sample::Index>(),
        any::<bool>(),
    )
        .prop_map(move |(k, edits, cut, dup)| {
            let mut b = files[k].clone();
            for (at, byte) in edits {
                let i = at.index(b.len().max(1));
                if i < b.len() {
                    // Digits stay digits half the time: numbers go wild, markup survives.
                    // Printable ASCII (other bytes only make invalid UTF-8).
                    b[i] = if b[i].is_ascii_digit() && byte % 2 == 0 {
                        b'0' + byte % 10
                    } else {
                        32 + byte % 95
                    };
                }
            }
            if dup {
                // Splice a copy of the middle back in: repeated and unbalanced elements.
                let i = cut.index(b.len().max(1));
                let tail = b[i..].to_vec();
                b.truncate(i);
                b.extend_from_slice(&tail[..tail.len() / 2]);
                b.extend_from_slice(&tail);
            }
            b
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn mutated_real_files_never_panic(data in mutated_real_file()) {
        let opt = SvgOptions {
            hatch: Some((1.0, 15.0)),
            text_font: Some("futural".into()),
            ..SvgOptions::default()
        };
        if let Ok(d) = read_svg(&data, &opt) {
            let route = Route::closed(Pt::new(0.0, 0.0));
            let quick = PlanOptions {
                effort: Effort { kicks: 1, time_limit: Duration::from_millis(100), window: 3 },
                ..PlanOptions::default()
            };
            let passes: Vec<Pass> = d
                .layers
                .iter()
                .map(|l| Pass { name: l.name.clone(), strokes: plan(&l.strokes, route, &quick) })
                .collect();
            let g = to_gcode_passes(&passes, &GcodeOptions { route, arcs: Some(0.01), ..GcodeOptions::default() });
            prop_assert!(g.lines().all(|l| l.len() <= LINE_MAX));
        }
    }
}
