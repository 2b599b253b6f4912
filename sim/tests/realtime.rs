//! Real-time commands through the virtual board: feed hold and resume keep every step,
//! status reports follow the machine, soft reset at rest keeps the position.

use inkstep_core::machine::MotionControl;
use inkstep_core::settings::Settings;
use inkstep_sim::board::{Board, StepEvent};

fn text(b: &mut Board) -> String {
    String::from_utf8(b.usb_read()).unwrap()
}

fn run_ms(b: &mut Board, ms: u64, ev: &mut Vec<StepEvent>) {
    let until = b.now() + Board::ms_to_ticks(ms);
    b.run_until(until, &mut |e| ev.push(e));
}

/// The answer to `?`: the protocol tick takes the byte, the next one sends it.
fn status(b: &mut Board, ev: &mut Vec<StepEvent>) -> String {
    text(b);
    b.usb_write(b"?");
    run_ms(b, 2, ev);
    let t = text(b);
    t.lines()
        .find(|l| l.starts_with('<'))
        .unwrap_or("")
        .to_string()
}

#[test]
fn feed_hold_and_resume_lose_no_step() {
    let mut b = Board::new(Settings::default());
    let mut ev = Vec::new();
    let g = b"G21 G90\nG1 X60 Y20 F3000\nG1 X0 Y40\n";
    assert_eq!(b.usb_write(g), g.len());
    run_ms(&mut b, 500, &mut ev);
    assert!(status(&mut b, &mut ev).starts_with("<Run|"));
    b.usb_write(b"!");
    run_ms(&mut b, 400, &mut ev);
    let held_at = b.pipeline.side().exec.position();
    let st = status(&mut b, &mut ev);
    assert!(st.starts_with("<Hold:0|"), "{st}");
    run_ms(&mut b, 500, &mut ev);
    assert_eq!(
        b.pipeline.side().exec.position(),
        held_at,
        "nothing moves while held"
    );
    b.usb_write(b"~");
    assert!(b.run_to_idle(Board::ms_to_ticks(60_000), &mut |e| ev.push(e)));
    assert_eq!(b.pipeline.side().exec.position(), [0, 3200, 0]);
    let x: u32 = ev.iter().filter(|e| e.step & 1 != 0).count() as u32;
    let y: u32 = ev.iter().filter(|e| e.step & 2 != 0).count() as u32;
    assert_eq!((x, y), (4800 + 4800, 1600 + 1600));
    assert!(status(&mut b, &mut ev).starts_with("<Idle|MPos:0.000,40.000,0.000"));
}

#[test]
fn dwell_waits_after_the_moves_before_it() {
    let mut b = Board::new(Settings::default());
    let mut ev = Vec::new();
    b.usb_write(b"G21 G90\nG1 X10 F3000\nG4 P0.5\nG1 X0\n");
    assert!(b.run_to_idle(Board::ms_to_ticks(60_000), &mut |e| ev.push(e)));
    // The last step out and the first step back are at least the dwell apart.
    let turn = ev.iter().position(|e| e.pos[0] == 800).unwrap();
    let gap = (ev[turn + 1].t - ev[turn].t) as f64 / inkstep_sim::board::TICK_HZ as f64;
    assert!((0.5..0.6).contains(&gap), "{gap}");
    assert_eq!(ev.last().unwrap().pos, [0, 0, 0]);
}

#[test]
fn soft_reset_at_rest_keeps_the_position() {
    let mut b = Board::new(Settings::default());
    let mut ev = Vec::new();
    b.usb_write(b"G21 G90\nG1 X5 Y5 F3000\n");
    assert!(b.run_to_idle(Board::ms_to_ticks(60_000), &mut |e| ev.push(e)));
    b.usb_write(&[0x18]);
    run_ms(&mut b, 2, &mut ev);
    let t = text(&mut b);
    assert!(t.contains("Grbl 1.1h"), "{t}");
    assert!(!t.contains("ALARM"), "{t}");
    assert!(status(&mut b, &mut ev).starts_with("<Idle|MPos:5.000,5.000,0.000"));
}

#[test]
fn servo_pen_moves_after_the_steps_before_it_and_waits_its_lift_time() {
    let mut b = Board::new(Settings::default());
    let mut ev = Vec::new();
    // $201=1: servo pen; $204: lift time 150 ms by default.
    b.usb_write(b"$201=1\n");
    assert!(b.run_to_idle(Board::ms_to_ticks(1_000), &mut |e| ev.push(e)));
    b.usb_write(b"G21 G90\nM3\nG1 X10 F3000\nM5\nG1 X0\n");
    let mut pen_up_at_pos = None;
    let mut last_down = true;
    for _ in 0..5_000 {
        run_ms(&mut b, 1, &mut ev);
        if last_down && !b.pipeline.pen_down() && pen_up_at_pos.is_none() && !ev.is_empty() {
            pen_up_at_pos = Some(b.pipeline.side().exec.position());
        }
        last_down = b.pipeline.pen_down();
        if b.is_idle() && ev.last().map(|e| e.pos) == Some([0, 0, 0]) {
            break;
        }
    }
    let pos = pen_up_at_pos.expect("the pen was lifted");
    assert_eq!(
        pos,
        [800, 0, 0],
        "the pen lifts at the end of the line, not before"
    );
    let turn = ev.iter().position(|e| e.pos[0] == 800).unwrap();
    let gap = (ev[turn + 1].t - ev[turn].t) as f64 / inkstep_sim::board::TICK_HZ as f64;
    assert!((0.15..0.2).contains(&gap), "lift time {gap}");
}

/// The feed of `FS:` in a status line.
fn fs(st: &str) -> f64 {
    let f = st.split('|').find_map(|p| p.strip_prefix("FS:")).unwrap();
    f.split(',').next().unwrap().parse().unwrap()
}

/// `FS:` is the real feed mid-move (it said 0, or the start rate, on moves prepared in
/// segments), also after a hold and resume, and 0 at rest (issue 23).
#[test]
fn the_status_report_gives_the_real_feed_at_cruise() {
    let mut b = Board::new(Settings::default());
    let mut ev = Vec::new();
    for (line, feed) in [
        ("G21 G90 G1 X60 F1500\n", 1500.0),
        ("G1 X160 F3000\n", 3000.0),
    ] {
        b.usb_write(line.as_bytes());
        run_ms(&mut b, 1000, &mut ev);
        let st = status(&mut b, &mut ev);
        assert!(st.starts_with("<Run|"), "{st}");
        assert!((fs(&st) - feed).abs() <= feed * 0.01, "{line}: {st}");
        assert!(b.run_to_idle(Board::ms_to_ticks(60_000), &mut |e| ev.push(e)));
        assert_eq!(fs(&status(&mut b, &mut ev)), 0.0);
    }
    b.usb_write(b"G1 X0 F600\n");
    run_ms(&mut b, 500, &mut ev);
    b.usb_write(b"!");
    run_ms(&mut b, 500, &mut ev);
    b.usb_write(b"~");
    run_ms(&mut b, 1000, &mut ev);
    let st = status(&mut b, &mut ev);
    assert!((fs(&st) - 600.0).abs() <= 6.0, "after a resume: {st}");
}

/// `!` at rest holds the next move until `~`, and a G4 dwell reports Idle, as Grbl.
#[test]
fn hold_at_rest_waits_for_cycle_start_and_a_dwell_is_idle() {
    let mut b = Board::new(Settings::default());
    let mut ev = Vec::new();
    b.usb_write(b"!");
    run_ms(&mut b, 5, &mut ev);
    b.usb_write(b"G21 G91 G1 X5 F600\n");
    run_ms(&mut b, 500, &mut ev);
    assert!(ev.is_empty(), "the move waits for ~");
    assert!(status(&mut b, &mut ev).starts_with("<Hold:0|"));
    b.usb_write(b"~");
    assert!(b.run_to_idle(Board::ms_to_ticks(60_000), &mut |e| ev.push(e)));
    assert_eq!(b.pipeline.side().exec.position(), [400, 0, 0]);
    b.usb_write(b"G4 P1\n");
    run_ms(&mut b, 300, &mut ev);
    assert!(
        status(&mut b, &mut ev).starts_with("<Idle|"),
        "during the dwell"
    );
}
