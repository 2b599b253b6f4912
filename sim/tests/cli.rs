//! The `cargo sim` commands as a user runs them: run (trace, PNG, SVG, exit codes),
//! demo and --keys (files written), plot and profiles.

use std::path::Path;
use std::process::{Command, Output};

fn sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inkstep-sim"))
        .args(args)
        .output()
        .unwrap()
}

fn png_size(path: &Path) -> (u32, u32) {
    let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let r = d.read_info().unwrap();
    (r.info().width, r.info().height)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn run_writes_a_trace_of_step_events_and_the_drawing() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("t.gcode");
    std::fs::write(&g, "G21 G90\nG1 X3 Y1 F1200\nG2 X3 Y1 I1 J0\nG0 X0 Y0\n").unwrap();
    let (trace, png, svg) = (
        dir.path().join("t.csv"),
        dir.path().join("t.png"),
        dir.path().join("t.svg"),
    );
    let out = sim(&[
        "run",
        s(&g),
        "--trace",
        s(&trace),
        "--png",
        s(&png),
        "--svg",
        s(&svg),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&trace).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_us,x,y,z"));
    let rows: Vec<(f64, [i32; 3])> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].parse().unwrap(),
                [
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                    f[3].parse().unwrap(),
                ],
            )
        })
        .collect();
    let mut prev = (0.0, [0, 0, 0]);
    let mut shared = 0;
    for &(t, p) in &rows {
        // One row per interrupt: time moves on, every axis moves at most one step.
        assert!(t > prev.0, "{t} after {}", prev.0);
        let moved: Vec<i32> = (0..3).map(|a| (p[a] - prev.1[a]).abs()).collect();
        assert!(moved.iter().all(|&d| d <= 1) && moved.contains(&1), "{p:?}");
        if moved[0] == 1 && moved[1] == 1 {
            shared += 1;
        }
        prev = (t, p);
    }
    assert!(
        shared > 0,
        "axes stepping in the same interrupt share a row"
    );
    assert_eq!(rows.last().unwrap().1, [0, 0, 0]);
    assert!(rows.iter().any(|r| r.1 == [240, 80, 0]));
    let (w, h) = png_size(&png);
    assert!(w > 100 && h > 20);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<polyline"));
    assert!(String::from_utf8_lossy(&out.stdout).contains("final position 0,0,0"));
}

#[test]
fn run_fails_and_names_the_lines_on_errors() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("bad.gcode");
    std::fs::write(&g, "G1 X1 F600\nG1 X2 Q4\nG0 X0\n").unwrap();
    let out = sim(&["run", s(&g)]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 2: G1 X2 Q4 -> error:"), "{err}");
}

#[test]
fn demo_writes_screens_drawing_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = sim(&["demo", "--out", s(dir.path())]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("keypad: sine and star") && text.contains("G-code: flower"),
        "{text}"
    );
    assert!(text.contains("final position 0,0,0"), "{text}");
    let mut lcds: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".png") && n != "drawing.png")
        .collect();
    lcds.sort();
    assert_eq!(lcds.len(), 13, "{lcds:?}");
    for n in &lcds {
        assert_eq!(
            png_size(&dir.path().join(n)),
            png_size(&dir.path().join(&lcds[0])),
            "{n}"
        );
    }
    // Boot, menu and drawing screens are different pictures.
    let a = std::fs::read(dir.path().join("01_boot.png")).unwrap();
    let b = std::fs::read(dir.path().join("02_menu.png")).unwrap();
    let c = std::fs::read(dir.path().join("06_sine_drawing.png")).unwrap();
    assert!(a != b && b != c);
    let svg = std::fs::read_to_string(dir.path().join("drawing.svg")).unwrap();
    assert!(
        svg.matches("<polyline").count() >= 3,
        "sine, star and flower strokes"
    );
    let (w, h) = png_size(&dir.path().join("drawing.png"));
    assert!(w >= 900 && h > 200, "{w}x{h}");
}

#[test]
fn keys_script_jogs_and_snapshots() {
    let dir = tempfile::tempdir().unwrap();
    // After the boot screen: '1' opens manual jog, holding '6' jogs +X for one second.
    let out = sim(&[
        "demo",
        "--out",
        s(dir.path()),
        "--keys",
        "wait:1800 1 6:1000 wait:500 lcd:jog",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.path().join("jog.png").exists());
    let text = String::from_utf8_lossy(&out.stdout);
    let pos = text.split("final position ").nth(1).unwrap();
    let x: i32 = pos.split(',').next().unwrap().parse().unwrap();
    let y: i32 = pos.split(',').nth(1).unwrap().parse().unwrap();
    assert!(x > 100 && y == 0, "{text}");
    let bad = sim(&["demo", "--out", s(dir.path()), "--keys", "1 E"]);
    assert_eq!(bad.status.code(), Some(2));
}

#[test]
fn plots_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("l.gcode");
    std::fs::write(&g, "G21 G90\nG1 X20 Y5 F3000\nG1 X0 Y0\n").unwrap();
    let trace = dir.path().join("l.csv");
    assert!(sim(&["run", s(&g), "--trace", s(&trace)]).status.success());
    let speed = dir.path().join("speed.png");
    assert!(sim(&["plot", s(&trace), "-o", s(&speed)]).status.success());
    assert_eq!(png_size(&speed), (1100, 800));
    let prof = dir.path().join("profiles.png");
    let out = sim(&["profiles", "-o", s(&prof)]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("S-curve (cosine)"));
    assert!(png_size(&prof).0 > 1000);
}
