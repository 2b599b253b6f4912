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

/// The seconds in "estimated job time ... (12.345 s" on stdout.
fn estimate_in(out: &std::process::Output) -> f64 {
    let s = String::from_utf8_lossy(&out.stdout);
    let k = s.find("estimated job time").expect("an estimate");
    let rest = &s[k..];
    let open = rest.find(" (").unwrap() + 2;
    rest[open..].split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn estimate_and_preview_give_the_firmwares_time_with_the_settings_given() {
    let g = tmp("e.gcode");
    host(&["text", "Hi", "--size", "12", "-o", g.to_str().unwrap()]);
    let file = g.to_str().unwrap();
    let plain = estimate_in(&host(&["estimate", file]));
    // The program on the simulator's board with the firmware's defaults.
    let text = std::fs::read_to_string(&g).unwrap();
    let r = inkstep_sim::run::run_gcode(&text, inkstep_sim::run::Flow::CharCount(128));
    let sim = r.rel(r.end) as f64 / inkstep_sim::board::TICK_HZ as f64;
    assert!((plain - sim).abs() < 0.01 * sim, "{plain} vs {sim}");
    // Slower acceleration from a flag, and a servo pen from a $$ listing.
    let slow = estimate_in(&host(&[
        "estimate", file, "--set", "120=20", "--set", "121=20",
    ]));
    assert!(slow > plain * 1.2, "{slow} vs {plain}");
    let listing = tmp("settings.txt");
    std::fs::write(&listing, "$201=1\n$204=600\nok\n").unwrap();
    let servo = estimate_in(&host(&[
        "estimate",
        file,
        "--settings",
        listing.to_str().unwrap(),
    ]));
    assert!((servo - plain).abs() > 0.5, "{servo} vs {plain}");
    // preview prints the same figure as estimate.
    let png = tmp("e.png");
    let p = estimate_in(&host(&["preview", file, "-o", png.to_str().unwrap()]));
    assert!((p - plain).abs() < 1e-3, "{p} vs {plain}");
    // A bad flag is an error naming it.
    let bad = Command::new(env!("CARGO_BIN_EXE_inkstep-host"))
        .args(["estimate", file, "--set", "110=fast"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("110=fast"));
}
