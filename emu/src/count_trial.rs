//! Rate trials that count every pulse (issue 20, point 3): a job of realistic G-code
//! lines (25 to 40 bytes, `G1 X12.345 Y0.000 F33750.0`) streamed over USB with
//! character counting, `?` every 100 ms, the LCD drawing (the trial starts 2 s after
//! power-up, when its power-up delays are long over), along one axis or point by
//! point on a diagonal (`$212=0`). The final position is checked pulse by pulse per
//! axis: the rising edges on the step pins, each signed by the direction pin's level
//! at that edge (the board model's count), against the commanded steps and against
//! the `MPos` the firmware reports at rest.
//!
//! Why it is shaped so: a step output that can repeat or drop a pulse shows itself
//! only in the count, never in the intervals the older rate trials looked at; long
//! lines fill whole 64-byte USB packets, whose copy is the longest masked section of
//! the image, and the LCD's drawing adds its own load. Every trial also reads the
//! firmware's count of late step armings (see `src/steps.rs`) when the image has one.

use crate::clock::{T_PER_MS, T_PER_S, T_PER_US};
use crate::session::Session;
use inkstep_serial::grbl::{parse_reply, Reply};
use inkstep_serial::sender::Flow;
use std::path::Path;

/// Steps per mm of X and Y in the trials: with `$110 = 33751` mm/min one axis may step
/// just above the planner's cap (`MAX_STEP_RATE`).
pub const STEPS_PER_MM: f64 = 160.0;

/// The shape of a trial's moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Course {
    /// Along X (Y stays at 0): one event per X step.
    AlongX,
    /// 45 degrees, point by point (`$212=0`): one axis per event.
    Diagonal,
}

impl Course {
    pub fn name(self) -> &'static str {
        match self {
            Course::AlongX => "along X",
            Course::Diagonal => "diagonal, point by point",
        }
    }

    /// Step events per mm of path.
    fn events_per_mm(self) -> f64 {
        match self {
            Course::AlongX => STEPS_PER_MM,
            Course::Diagonal => 2.0 * STEPS_PER_MM / std::f64::consts::SQRT_2,
        }
    }
}

/// What one trial commanded, what the pins did and what the firmware reported.
#[derive(Clone, Debug)]
pub struct Counted {
    pub course: Course,
    /// Step events per second the program asks for.
    pub requested: f64,
    /// Step events per second at cruise (the median interval of the middle half).
    pub cruise: f64,
    pub lines: usize,
    /// Shortest and longest line, bytes with the newline.
    pub line_bytes: (usize, usize),
    /// `?` sent while the job streamed, and status reports that came back meanwhile.
    pub questions: usize,
    pub reports: usize,
    /// LCD writes (instructions and data) during the trial: it was drawing.
    pub lcd_writes: u64,
    /// The program's end point in steps.
    pub commanded: [i64; 3],
    /// Rising edges on each step pin, signed by the direction pin.
    pub pulses: [i64; 3],
    /// Rising edges on each step pin, unsigned (the moves go one way only, so this is
    /// the commanded distance too: an added pulse and a dropped one cannot cancel).
    pub edges: [u64; 3],
    /// `MPos` at rest, in steps.
    pub reported: [i64; 3],
    /// The firmware's count of late step armings during the trial, if it keeps one.
    pub late: Option<u32>,
    /// The count the firmware's log gave last (its LCD task logs the total since
    /// power-up when it grows), read 300 ms after the machine came to rest.
    pub logged_late: Option<u32>,
    /// The shortest interval between two step events of the trial, µs (rising edges:
    /// along X each is an X step, so no period of the X step pin was shorter).
    pub shortest_us: f64,
}

impl Counted {
    /// Pulses added (positive) or lost (negative) per axis.
    pub fn off_by(&self) -> [i64; 3] {
        [0, 1, 2].map(|a| self.pulses[a] - self.commanded[a])
    }

    /// Every pulse commanded came out once, no other, and the firmware says so too.
    pub fn exact(&self) -> bool {
        (0..3).all(|a| {
            self.pulses[a] == self.commanded[a]
                && self.reported[a] == self.commanded[a]
                && self.edges[a] == self.commanded[a].unsigned_abs()
        })
    }

    /// One line for a report.
    pub fn summary(&self) -> String {
        format!(
            "{}: asked {:.0} events/s, cruise {:.0}; {} lines of {}-{} bytes, {} `?` ({} answered), {} LCD writes; commanded X{} Y{}, pulses X{} Y{} (edges {} {}), MPos X{} Y{} steps; off by X{:+} Y{:+}; late armings {} (log: {})",
            self.course.name(),
            self.requested,
            self.cruise,
            self.lines,
            self.line_bytes.0,
            self.line_bytes.1,
            self.questions,
            self.reports,
            self.lcd_writes,
            self.commanded[0],
            self.commanded[1],
            self.pulses[0],
            self.pulses[1],
            self.edges[0],
            self.edges[1],
            self.reported[0],
            self.reported[1],
            self.off_by()[0],
            self.off_by()[1],
            self.late.map_or("not kept by this image".to_string(), |n| n.to_string()),
            self.logged_late.map_or("no line".to_string(), |n| n.to_string()),
        )
    }
}

/// The job: `G21 G90`, then lines of 2.000 to 2.499 mm of path (varied, so no two
/// neighbours are alike) at the feed that asks for `rate` events/s, for about
/// `seconds` of cruise. Returns the text and the end point in mm.
pub fn job(course: Course, rate: f64, seconds: f64) -> (String, [f64; 2]) {
    let feed = rate / course.events_per_mm() * 60.0;
    let want_mm = feed / 60.0 * seconds;
    let mut text = String::from("G21 G90\n");
    // In µm, so that every coordinate in the text is exact.
    let (mut x, mut y) = (0i64, 0i64);
    let mut path_mm = 0.0;
    let mut i = 0i64;
    while path_mm < want_mm || i < 20 {
        let d = 2000 + (i * 137) % 500;
        i += 1;
        x += d;
        path_mm += d as f64 / 1000.0;
        if course == Course::Diagonal {
            // d µm along each axis: sqrt 2 d of path.
            y += d;
            path_mm += d as f64 / 1000.0 * (std::f64::consts::SQRT_2 - 1.0);
        }
        text.push_str(&format!(
            "G1 X{:.3} Y{:.3} F{feed:.1}\n",
            x as f64 / 1000.0,
            y as f64 / 1000.0
        ));
    }
    (text, [x as f64 / 1000.0, y as f64 / 1000.0])
}

/// The firmware's late-arming counter: the `inkstep_late_step_armings` static of an
/// image that keeps one.
const LATE_SYMBOL: &str = "inkstep_late_step_armings";

/// Boot a board with `elf`, set it up for `course`, wait until 2 s after power-up,
/// then stream the job and count.
pub fn run(elf: &Path, course: Course, rate: f64, seconds: f64) -> Result<Counted, String> {
    run_with(elf, course, rate, seconds, &[])
}

/// [`run`] with more settings after the trial's own (`$0=20`, ...).
pub fn run_with(
    elf: &Path,
    course: Course,
    rate: f64,
    seconds: f64,
    settings: &[&str],
) -> Result<Counted, String> {
    let mut s = Session::new(elf, None)?;
    s.boot()?;
    let mut setup = vec!["$100=160", "$101=160", "$110=33751", "$111=33751"];
    setup.extend(["$120=20000", "$121=20000"]);
    if course == Course::Diagonal {
        setup.push("$212=0");
    }
    setup.extend(settings);
    for c in setup {
        let got = s.command(c, T_PER_S)?;
        if got.contains("error") {
            return Err(format!("{c}: {got}"));
        }
    }
    // The LCD's power-up (its init delays, the first full draw) is long over by then.
    if s.now() < 2 * T_PER_S {
        s.run_to(2 * T_PER_S)?;
    }
    let (text, end_mm) = job(course, rate, seconds);
    let lens: Vec<usize> = text.lines().skip(1).map(|l| l.len() + 1).collect();
    let line_bytes = (
        lens.iter().copied().min().unwrap_or(0),
        lens.iter().copied().max().unwrap_or(0),
    );
    let late_at = s.symbol(LATE_SYMBOL);
    let late_before = late_at.and_then(|a| s.read_u32(a));
    let lcd_before = s.m.state().board.lcd.writes;
    let first_step = s.m.state().board.steps.len();
    s.m.board().host.packets = Some(Vec::new());
    let mut next_q = s.now();
    let mut questions = 0;
    let r = s.stream(&text, Flow::CharCount(128), 600 * T_PER_S, |s| {
        if s.now() >= next_q {
            s.send(b"?");
            questions += 1;
            next_q = s.now() + 100 * T_PER_MS;
        }
        Ok(())
    })?;
    if !r.errors.is_empty() || !r.alarms.is_empty() {
        return Err(format!("refused: {:?} {:?}", r.errors, r.alarms));
    }
    let reports =
        s.m.board()
            .host
            .packets
            .take()
            .unwrap_or_default()
            .iter()
            .filter(|p| !p.out && p.data.contains(&b'<'))
            .count();
    let idle = s.wait_idle(600 * T_PER_S)?;
    let lcd_writes = s.m.state().board.lcd.writes - lcd_before;
    let reported = match parse_reply(&idle) {
        Reply::Status(st) if !st.work => st.pos.ok_or("no MPos in the report")?,
        _ => return Err(format!("not a machine-position report: {idle}")),
    };
    let late = match (late_at, late_before) {
        (Some(a), Some(b)) => s.read_u32(a).map(|n| n.wrapping_sub(b)),
        _ => None,
    };
    // Time for the LCD task (every 100 ms) to log the count.
    s.run_for(300 * T_PER_MS)?;
    let logged_late = s.m.state().log.as_ref().and_then(|log| {
        log.lines.iter().rev().find_map(|l| {
            let rest = l.split("step interrupt late ").nth(1)?;
            rest.split_whitespace().next()?.parse().ok()
        })
    });
    let b = &s.m.state().board;
    let steps = &b.steps[first_step..];
    let cruise = cruise_rate(steps.iter().map(|st| st.t).collect());
    let shortest = steps.windows(2).map(|w| w[1].t - w[0].t).min().unwrap_or(0);
    let to_steps = |mm: f64| (mm * STEPS_PER_MM).round() as i64;
    Ok(Counted {
        course,
        requested: rate,
        cruise,
        lines: lens.len(),
        line_bytes,
        questions,
        reports,
        lcd_writes,
        commanded: [to_steps(end_mm[0]), to_steps(end_mm[1]), 0],
        pulses: b.pos.map(i64::from),
        edges: b.step_edges,
        reported: reported.map(to_steps),
        late,
        logged_late,
        shortest_us: shortest as f64 / T_PER_US as f64,
    })
}

/// Step events per second at cruise: the median interval of the middle half.
fn cruise_rate(t: Vec<u64>) -> f64 {
    let n = t.len();
    if n < 8 {
        return 0.0;
    }
    let mut iv: Vec<u64> = t[n / 4..3 * n / 4]
        .windows(2)
        .map(|w| w[1] - w[0])
        .collect();
    iv.sort_unstable();
    T_PER_S as f64 / iv[iv.len() / 2].max(1) as f64
}
