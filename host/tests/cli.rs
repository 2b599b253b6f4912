//! The command line end to end: `text`, `svg` and `preview` write files
//! that parse back, and `plan-bench` prints its table.

use inkstep_host::toolpath::{check_grbl, parse, MoveKind};
use std::path::PathBuf;
use std::process::Command;

fn host(args: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("inkstep-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn text_to_gcode_to_preview() {
    let g = tmp("t.gcode");
    let png = tmp("t.png");
    host(&[
        "text",
        "机器人 Hi",
        "--size",
        "12",
        "-o",
        g.to_str().unwrap(),
    ]);
    let src = std::fs::read_to_string(&g).unwrap();
    check_grbl(&src).unwrap();
    let moves = parse(&src).unwrap();
    let xmax = moves.iter().map(|m| m.to.x).fold(0.0, f64::max);
    // Three 12 mm hanzi boxes, a 4.5 mm space, then "Hi" (narrower than two boxes).
    assert!(xmax > 40.5 && xmax < 40.5 + 24.0, "{xmax}");
    host(&[
        "preview",
        g.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--width",
        "400",
    ]);
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // Z pen, no reversal: still valid, and Z moves instead of M3/M5.
    host(&[
        "text",
        "Hi",
        "--pen",
        "z",
        "--z-up",
        "2",
        "--z-down",
        "-1",
        "--keep-direction",
        "-o",
        g.to_str().unwrap(),
    ]);
    let src = std::fs::read_to_string(&g).unwrap();
    check_grbl(&src).unwrap();
    assert!(src.contains("G1 Z-1") && src.contains("G0 Z2") && !src.contains("M3"));
}

#[test]
fn svg_to_gcode() {
    let svg = tmp("d.svg");
    let g = tmp("d.gcode");
    std::fs::write(
        &svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="50mm" height="50mm" viewBox="0 0 50 50">
             <rect x="5" y="5" width="40" height="40" fill="none" stroke="black"/>
             <path d="M5 5 L45 45 M45 5 L5 45" stroke="black"/>
             <circle cx="25" cy="25" r="10" fill="none" stroke="black"/>
           </svg>"#,
    )
    .unwrap();
    host(&["svg", svg.to_str().unwrap(), "-o", g.to_str().unwrap()]);
    let src = std::fs::read_to_string(&g).unwrap();
    check_grbl(&src).unwrap();
    let moves = parse(&src).unwrap();
    let drawn: f64 = moves
        .iter()
        .filter(|m| m.kind == MoveKind::Draw)
        .map(|m| m.from.dist(m.to))
        .sum();
    // Square 160 mm, diagonals 2 x 56.57 mm, circle 62.83 mm (chords a bit less).
    let expect = 160.0 + 2.0 * 40f64.hypot(40.0) + std::f64::consts::TAU * 10.0;
    assert!((drawn - expect).abs() < 0.1, "{drawn} vs {expect}");
}

#[test]
fn plan_bench_prints_its_table() {
    let out = host(&["plan-bench", "一帆风顺", "--vpype", "", "--kicks", "5"]);
    let s = String::from_utf8_lossy(&out.stdout);
    for row in [
        "natural (writing order)",
        "greedy nearest end",
        "inkstep plan (default)",
    ] {
        assert!(s.contains(row), "{s}");
    }
}
