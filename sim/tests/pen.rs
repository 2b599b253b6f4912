//! The pen on the virtual board (issue 24): `M3 S` heights for the servo and the Z
//! pen, separate lift and drop times and a servo speed, the pen lifted while the
//! machine waits (feed hold, M0, M6) and dropped at the same point on resume, the
//! pen up after an abort, `(MSG, ...)`, the M6 pen change with its LCD prompt, and
//! `Ln:` / `A:S` in the status report.

use inkstep_core::hmi::PromptView;
use inkstep_core::motion::PEN_FULL;
use inkstep_core::settings::Settings;
use inkstep_sim::board::{Board, StepEvent};

/// One millisecond of the board: the servo's pulse and the position at its end.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sample {
    servo: Option<u32>,
    pos: [i32; 3],
}

struct Run {
    b: Board,
    steps: Vec<StepEvent>,
    samples: Vec<Sample>,
    /// Bytes still to send.
    to_send: Vec<u8>,
    out: String,
}

impl Run {
    fn new(settings: &[(u16, f32)]) -> Run {
        let mut s = Settings::default();
        for &(n, v) in settings {
            s.set(n, v).unwrap();
        }
        Run {
            b: Board::new(s),
            steps: Vec::new(),
            samples: Vec::new(),
            to_send: Vec::new(),
            out: String::new(),
        }
    }

    fn send(&mut self, text: &str) {
        self.to_send.extend_from_slice(text.as_bytes());
    }

    fn ms(&mut self, ms: u64) {
        for _ in 0..ms {
            if !self.to_send.is_empty() {
                let n = self.b.usb_write(&self.to_send);
                self.to_send.drain(..n);
            }
            let until = self.b.now() + Board::ms_to_ticks(1);
            let steps = &mut self.steps;
            self.b.run_until(until, &mut |e| steps.push(e));
            self.samples.push(Sample {
                servo: self.b.servo_pulse_us,
                pos: self.b.pipeline.side().exec.position(),
            });
            self.out
                .push_str(&String::from_utf8(self.b.usb_read()).unwrap());
        }
    }

    /// Runs until everything is sent and the board is idle (at most 60 s).
    fn until_idle(&mut self) {
        for _ in 0..60_000 {
            self.ms(1);
            if self.to_send.is_empty() && self.b.is_idle() {
                self.ms(5);
                return;
            }
        }
        panic!("not idle: {}", self.out);
    }

    /// The answer to `?`.
    fn status(&mut self) -> String {
        let from = self.out.len();
        self.b.usb_write(b"?");
        self.ms(3);
        self.out[from..]
            .lines()
            .find(|l| l.starts_with('<'))
            .unwrap_or("")
            .to_string()
    }

    fn servo(&self) -> u32 {
        self.b.servo_pulse_us.expect("a servo pen")
    }

    /// The positions stepped while the pen was down, in order.
    fn strokes(&self) -> Vec<[i32; 3]> {
        self.steps
            .iter()
            .filter(|e| e.servo_down)
            .map(|e| e.pos)
            .collect()
    }

    /// The longest time (ms) the servo was at `down_us` with XY standing still.
    fn longest_still_down(&self, down_us: u32) -> usize {
        let (mut run, mut worst) = (0, 0);
        for w in self.samples.windows(2) {
            let still = w[0].pos[..2] == w[1].pos[..2];
            if still && w[1].servo == Some(down_us) {
                run += 1;
                worst = worst.max(run);
            } else {
                run = 0;
            }
        }
        worst
    }
}

fn pulse(settings: &[(u16, f32)], level: u16) -> u32 {
    let mut s = Settings::default();
    for &(n, v) in settings {
        s.set(n, v).unwrap();
    }
    s.pen_servo_pulse_us(level)
}

const SERVO: &[(u16, f32)] = &[(201, 1.0), (202, 90.0), (203, 30.0)];

/// `M3 S<v>`: the servo pulse in proportion within $31..$30 (S max fully down); `M3`
/// with no S is fully down as before, `M5` up; a Z pen goes to its place between
/// $205 and $206.
#[test]
fn m3_s_sets_the_servo_pulse_and_the_z_height_in_proportion() {
    let mut r = Run::new(SERVO);
    let (up, down) = (pulse(SERVO, 0), pulse(SERVO, PEN_FULL));
    assert_eq!(
        (pulse(SERVO, 500), pulse(SERVO, 250)),
        (1166, 1333),
        "60 and 75 deg"
    );
    // 90 and 30 deg (as before: 90 deg comes out 1 us short of 1500).
    assert_eq!((up, down), (1499, 833));
    r.ms(5);
    assert_eq!(r.servo(), up);
    for (line, want) in [
        ("M3", down),
        ("M5", up),
        ("M3 S500", pulse(SERVO, 500)),
        ("S250", pulse(SERVO, 250)),
        ("S1000", down),
        ("M5", up),
        ("M3", down),
    ] {
        r.send(&format!("{line}\n"));
        r.until_idle();
        assert_eq!(r.servo(), want, "{line}");
    }
    assert!(!r.out.contains("error"), "{}", r.out);

    let mut z = Run::new(&[]);
    for (line, steps) in [
        ("M3 S500", -400),
        ("M3 S1000", -800),
        ("M5", 0),
        ("M3 S250", -200),
    ] {
        z.send(&format!("{line}\n"));
        z.until_idle();
        assert_eq!(
            z.samples.last().unwrap().pos[2],
            steps,
            "{line}: Z at 400 steps/mm"
        );
    }
}

/// The time from the last step before a pen command to the first after it.
fn gap_ms(r: &Run, x_before: i32) -> f64 {
    let i = r.steps.iter().rposition(|e| e.pos[0] == x_before).unwrap();
    (r.steps[i + 1].t - r.steps[i].t) as f64 / inkstep_sim::board::TICK_HZ as f64 * 1000.0
}

/// `$207` drop and `$204` lift times are waited separately; `$208` adds the turn at
/// the servo speed (60 deg at 600 deg/s = 100 ms). Defaults: 150 ms each way.
#[test]
fn the_motion_waits_the_drop_and_lift_times_and_the_turn() {
    let program = "G1 X5 F3000\nM3\nG1 X10\nM5\nG1 X15\n";
    for (extra, drop, lift) in [
        (&[(204, 100.0), (207, 300.0)][..], 300.0, 100.0),
        (
            &[(204, 100.0), (207, 300.0), (208, 600.0)][..],
            400.0,
            200.0,
        ),
        (&[][..], 150.0, 150.0),
    ] {
        let mut settings = SERVO.to_vec();
        settings.extend_from_slice(extra);
        let mut r = Run::new(&settings);
        r.send(program);
        r.until_idle();
        let (d, l) = (gap_ms(&r, 400), gap_ms(&r, 800));
        // A step's own period and a millisecond per servo frame at most on top.
        assert!(d >= drop && d < drop + 8.0, "{extra:?}: drop {d} ms");
        assert!(l >= lift && l < lift + 8.0, "{extra:?}: lift {l} ms");
        assert_eq!(r.samples.last().unwrap().pos, [1200, 0, 0]);
    }
}

/// A feed hold in the middle of a stroke: the pen lifts once XY stands, stays up
/// while held, drops at the same point on `~` and waits the drop time before XY
/// moves on. The strokes are exactly those of the uninterrupted run, and the pen is
/// never down with XY still for longer than the drop time.
#[test]
fn a_hold_mid_stroke_lifts_the_pen_and_resume_draws_the_same_strokes() {
    let mut settings = SERVO.to_vec();
    settings.push((207, 200.0));
    let program = "G0 X10\nM3\nG1 X60 F1200\nG1 Y30\nM5\nG0 X0 Y0\n";
    let (up, down) = (pulse(&settings, 0), pulse(&settings, PEN_FULL));

    let mut plain = Run::new(&settings);
    plain.send(program);
    plain.until_idle();

    // `!` and the safety door (0x84) alike.
    for (stop, state) in [(b'!', "<Hold:0|"), (0x84, "<Door:0|")] {
        let mut held = Run::new(&settings);
        held.send(program);
        held.ms(1500);
        assert_eq!(held.servo(), down, "drawing");
        held.b.usb_write(&[stop]);
        held.ms(400);
        let st = held.status();
        assert!(st.starts_with(state), "{st}");
        assert_eq!(held.servo(), up, "lifted once XY stands");
        let at = held.samples.last().unwrap().pos;
        held.ms(1000);
        assert_eq!(held.samples.last().unwrap().pos, at, "still");
        assert_eq!(held.servo(), up, "up while held");
        held.b.usb_write(b"~");
        held.ms(150);
        assert_eq!(
            (held.servo(), held.samples.last().unwrap().pos),
            (down, at),
            "down, waiting"
        );
        held.until_idle();

        assert_eq!(held.strokes(), plain.strokes(), "the same strokes");
        assert!(plain.strokes().len() > 4000);
        // The drop time, then the first step of a start from rest: 1/80 mm from the
        // start rate (1 mm/s) at 200 mm/s^2 takes 7.2 ms.
        let still = held.longest_still_down(down);
        assert!(still <= 200 + 8, "down with XY still for {still} ms");
        assert_eq!(
            still,
            plain.longest_still_down(down),
            "as at the stroke's start"
        );
        assert_eq!(held.samples.last().unwrap().pos, [0, 0, 0]);
    }
}

/// A Z-axis pen ($201=0): a feed hold or the safety door in the middle of a stroke
/// lifts Z to $205 once XY stands (the state shows Hold:0 / Door:0 only once it is
/// up), Z stays up while held, and `~` takes it back to the very step it left before
/// XY moves on. The pen-down steps are exactly those of the uninterrupted run and the
/// job ends where it would have.
#[test]
fn a_hold_mid_stroke_lifts_the_z_pen_and_resume_draws_the_same_strokes() {
    let s = Settings::default();
    let z = |mm: f32| (mm * s.steps_per_mm(2)).round() as i32;
    let (up, down) = (z(s.pen_z_up()), z(s.pen_z_down()));
    assert_ne!(up, down);
    let program = "G0 X10\nM3\nG1 X60 F1200\nG1 Y30\nM5\nG0 X0 Y0\n";
    // The XY points stepped with Z at the down place, in order (the arrival of Z
    // itself once).
    let strokes = |r: &Run| {
        let mut d: Vec<[i32; 2]> = r
            .steps
            .iter()
            .filter(|e| e.pos[2] == down)
            .map(|e| [e.pos[0], e.pos[1]])
            .collect();
        d.dedup();
        d
    };

    let mut plain = Run::new(&[]);
    plain.send(program);
    plain.until_idle();
    assert!(strokes(&plain).len() > 4000);

    for (stop, state) in [(b'!', "<Hold:0|"), (0x84, "<Door:0|")] {
        let mut held = Run::new(&[]);
        held.send(program);
        held.ms(1500);
        assert_eq!(held.samples.last().unwrap().pos[2], down, "drawing");
        let from = held.steps.len();
        held.b.usb_write(&[stop]);
        let mut st = String::new();
        for _ in 0..100 {
            held.ms(20);
            st = held.status();
            if st.starts_with(state) {
                break;
            }
        }
        assert!(st.starts_with(state), "{st}");
        let at = held.samples.last().unwrap().pos;
        assert_eq!(at[2], up, "Z up once at rest");
        // XY stood still from the first Z step on.
        let lift = from
            + held.steps[from..]
                .iter()
                .position(|e| e.pos[2] != down)
                .unwrap();
        assert!(
            held.steps[lift..].iter().all(|e| e.pos[..2] == at[..2]),
            "XY still while Z rises"
        );
        held.ms(1000);
        assert_eq!(held.samples.last().unwrap().pos, at, "up while held");

        let from = held.steps.len();
        held.b.usb_write(b"~");
        held.until_idle();
        let xy = from
            + held.steps[from..]
                .iter()
                .position(|e| e.pos[..2] != at[..2])
                .unwrap();
        assert_eq!(
            held.steps[xy - 1].pos,
            [at[0], at[1], down],
            "Z back down before XY moves on"
        );
        assert_eq!(strokes(&held), strokes(&plain), "the same strokes");
        assert_eq!(held.samples.last().unwrap().pos, [0, 0, up]);
        assert_eq!(
            held.samples.last().unwrap().pos,
            plain.samples.last().unwrap().pos
        );
    }
}

/// `M0` with a Z pen down: Z goes up to $205 while paused (Hold:0 once it is up) and
/// `~` brings it back to $206 before the next stroke starts, which is drawn whole.
#[test]
fn m0_lifts_the_z_pen_and_cycle_start_lowers_it_before_the_next_stroke() {
    let mut r = Run::new(&[]);
    r.send("M3\nG1 X10 F600\nM0\nG1 X20\nM5\n");
    r.ms(3000);
    assert!(
        r.status().starts_with("<Hold:0|MPos:10.000,0.000,0.000"),
        "Z up while paused"
    );
    let from = r.steps.len();
    r.b.usb_write(b"~");
    r.until_idle();
    let after = &r.steps[from..];
    let x = after.iter().position(|e| e.pos[0] > 800).unwrap();
    assert!(
        x > 0 && after[x - 1].pos == [800, 0, -800],
        "down at X10 first"
    );
    assert!(
        after[x].pos == [801, 0, -800],
        "the stroke drawn whole, pen down"
    );
    assert_eq!(r.samples.last().unwrap().pos, [1600, 0, 0]);
}

/// A soft reset in the middle of a stroke leaves the pen up, and the next `M3` drops
/// it again.
#[test]
fn an_abort_leaves_the_pen_up() {
    let mut r = Run::new(SERVO);
    r.send("M3\nG1 X100 F600\n");
    r.ms(500);
    assert_eq!(r.servo(), pulse(SERVO, PEN_FULL));
    r.b.usb_write(&[0x18]);
    r.ms(5);
    assert_eq!(r.servo(), pulse(SERVO, 0));
    assert!(r.out.contains("ALARM:3"), "{}", r.out);
    r.send("$X\nM3\n");
    r.until_idle();
    assert_eq!(r.servo(), pulse(SERVO, PEN_FULL));
}

/// `M0` lifts the servo pen at rest and shows the pause prompt with the last
/// message; `~` drops it where it was before the next stroke.
#[test]
fn m0_pauses_with_the_pen_up_and_a_prompt() {
    let mut r = Run::new(SERVO);
    r.send("M3\nG1 X10 F600\n(MSG, Check the ink)\nM0\nG1 X20\nM5\n");
    r.ms(3000);
    assert!(r.out.contains("[MSG:Check the ink]\r\nok"), "{}", r.out);
    assert!(r.status().starts_with("<Hold:0|MPos:10.000,0.000"));
    assert_eq!(r.servo(), pulse(SERVO, 0), "up while paused");
    let prompt = r.b.ctl.hmi().prompt().copied();
    assert_eq!(prompt.map(|p| p.pen), Some(None));
    assert_eq!(prompt.unwrap().message.as_str(), "Check the ink");
    r.b.usb_write(b"~");
    r.until_idle();
    assert!(r.b.ctl.hmi().prompt().is_none());
    let first = r.strokes().iter().position(|p| p[0] > 800).unwrap();
    assert_eq!(r.strokes()[first][0], 801, "the second stroke drawn whole");
    assert_eq!(r.samples.last().unwrap().pos, [1600, 0, 0]);

    // A message alone shows at the LCD's bottom line for a while.
    r.send("(MSG,Hello there)\n");
    r.ms(10);
    assert_eq!(
        r.b.ctl.hmi().toast().map(|t| t.as_str()),
        Some("Hello there")
    );

    // M0 as the last line (nothing queued behind it): the pen lifts all the same.
    let mut r = Run::new(SERVO);
    r.send("M3\nG1 X10 F600\nM0\n");
    r.ms(3000);
    assert!(r.status().starts_with("<Hold:0|"));
    assert_eq!(r.servo(), pulse(SERVO, 0), "up while paused");
}

/// A layered job as the host tool writes it: `(MSG,pen N: name)` and `M6 TN`
/// between layers. The pen lifts, goes to the pen-change place, the board holds with
/// a message (what any Grbl sender shows), the LCD prompts for pen 2 with the
/// message; cycle start returns, drops the pen and draws the next layer. While the
/// first stroke runs the report says `Ln:30` and `A:S`.
#[test]
fn m6_changes_the_pen_at_the_pen_change_place_and_comes_back() {
    let mut settings = SERVO.to_vec();
    settings.extend_from_slice(&[(216, 1.0), (217, 0.0), (218, 0.0)]);
    let mut r = Run::new(&settings);
    r.send(
        "N10 G0 X20 Y10\nN20 M3\nN30 G1 X40 F300\nN35 M5\n(MSG,pen 2: red)\nN40 M6 T2\n\
         N45 M3\nN50 G1 X50\nN60 M5\n",
    );
    r.ms(1500);
    let st = r.status();
    assert!(
        st.starts_with("<Run|") && st.contains("|Ln:30|") && st.ends_with("|A:S>"),
        "{st}"
    );
    r.ms(6000);
    let st = r.status();
    assert!(st.starts_with("<Hold:0|MPos:0.000,0.000,0.000"), "{st}");
    assert!(!st.contains("A:S"), "{st}");
    assert!(r.out.contains("[MSG:pen 2: red]"), "{}", r.out);
    assert!(r
        .out
        .contains("[MSG:Pen change: pen 2, cycle start to continue]"));
    assert_eq!(r.servo(), pulse(&settings, 0));
    assert_eq!(
        r.b.ctl
            .hmi()
            .prompt()
            .map(|p: &PromptView| (p.pen, p.message.as_str().to_string())),
        Some((Some(2), "pen 2: red".to_string()))
    );
    r.b.usb_write(b"~");
    r.until_idle();
    assert!(!r.out.contains("error"), "{}", r.out);
    // The second layer starts where the first ended.
    let strokes = r.strokes();
    let second: Vec<_> = strokes.iter().filter(|p| p[0] > 3200).collect();
    assert_eq!(second.first().map(|p| (p[0], p[1])), Some((3201, 800)));
    assert_eq!(second.last().map(|p| (p[0], p[1])), Some((4000, 800)));
    assert!(
        strokes.iter().all(|p| p[1] == 800),
        "nothing drawn on the way"
    );
}
