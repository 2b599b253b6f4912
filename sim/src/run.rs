//! `cargo sim run`: a G-code file streamed through the real protocol handler at full
//! speed in virtual time, as a sender on the PC would stream it to the board.
//!
//! Owns the host-side loop only: the one Grbl [`Sender`] (inkstep-serial) writes what
//! flow control allows, the [`Board`] takes what its receive buffer can hold, responses
//! go back to the sender, and virtual time advances while both wait. Every line of the
//! file is sent as it is (the board answers comments and blanks too, like Grbl) and an
//! error does not stop the stream: the result lists each one with its line, and carries
//! every step event.

use crate::board::{Board, StepEvent, TICK_HZ};
use crate::render::{Drawing, Pen};
use crate::trace::{Row, Trace};
use inkstep_core::settings::{PenMode, Settings};
use inkstep_serial::grbl::Reply;
pub use inkstep_serial::sender::Flow;
use inkstep_serial::sender::{Answer, Event, Sender};

/// A line that was answered with an error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// 1-based line number in the file.
    pub line_no: usize,
    pub text: String,
    pub response: String,
}

/// Virtual time after which a run is abandoned (a job that never ends).
const TIME_LIMIT_S: u64 = 3600;

pub struct RunResult {
    pub events: Vec<StepEvent>,
    /// Timer tick when the first motion started.
    pub first_motion: Option<u64>,
    pub errors: Vec<LineError>,
    pub alarms: Vec<String>,
    pub messages: Vec<String>,
    pub lines: usize,
    pub final_pos: [i32; 3],
    /// Virtual time at the end of the stream, ticks.
    pub end: u64,
    pub timed_out: bool,
    /// At a time-out, the first real-time byte not sent because its step event never
    /// came: (that step's number, step events made). A byte timed from a step the
    /// job does not reach (a resume after a step the hold stopped short of) leaves a
    /// hold waiting for ever.
    pub realtime_waiting: Option<(usize, usize)>,
    /// Settings in force at the end (steps/mm etc. for the analysis).
    pub settings: Settings,
}

impl RunResult {
    /// Ticks of an event since the first motion started.
    pub fn rel(&self, t: u64) -> u64 {
        t - self.first_motion.unwrap_or(0)
    }

    /// The trace with times in microseconds since the first motion.
    pub fn trace(&self) -> Trace {
        let rows = self
            .events
            .iter()
            .map(|e| Row {
                t_us: self.rel(e.t) as f64 * 1e6 / TICK_HZ as f64,
                pos: e.pos,
            })
            .collect();
        Trace { rows }
    }

    /// Job time: first motion to the last step, seconds.
    pub fn job_time_s(&self) -> f64 {
        self.events
            .last()
            .map_or(0.0, |e| self.rel(e.t) as f64 / TICK_HZ as f64)
    }

    /// What the pen drew.
    pub fn drawing(&self) -> Drawing {
        drawing(&self.events, &self.settings)
    }

    pub fn ok(&self) -> bool {
        self.errors.is_empty() && self.alarms.is_empty() && !self.timed_out
    }
}

/// The drawing of step events from the origin: a Z-axis pen by its height, a servo pen
/// by the state the events carry.
pub fn drawing(events: &[StepEvent], s: &Settings) -> Drawing {
    let spmm = [f64::from(s.steps_per_mm(0)), f64::from(s.steps_per_mm(1))];
    match s.pen_mode() {
        PenMode::Servo => {
            Drawing::from_moves([0; 3], events.iter().map(|e| (e.pos, e.servo_down)), spmm)
        }
        PenMode::ZAxis => {
            let rows = events
                .iter()
                .map(|e| Row {
                    t_us: 0.0,
                    pos: e.pos,
                })
                .collect();
            Drawing::from_trace(&Trace { rows }, [0; 3], spmm, Pen::from_settings(s))
        }
    }
}

/// Streams `text` to a fresh board and runs until every line is answered and the
/// machine is idle.
pub fn run_gcode(text: &str, flow: Flow) -> RunResult {
    let mut board = Board::new(Settings::default());
    run_on(&mut board, text, flow)
}

/// Streams `text` to `board` (which may have run before).
pub fn run_on(board: &mut Board, text: &str, flow: Flow) -> RunResult {
    run_on_with(board, text, flow, &mut |_| {})
}

/// Real-time bytes sent at a time after the first step (`cargo sim run --realtime`,
/// and the same option of `cargo emu run`, so that both get them at the same moment
/// of the job: `.ci/emu-random`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Realtime {
    pub after_step: usize,
    /// Time after the first step, microseconds.
    pub at_us: u64,
    pub bytes: Vec<u8>,
}

impl Realtime {
    /// `250ms:!`, `1.5s:~`, `700ms:0x91` (a byte in hex), `40ms:0x91,0x91`.
    pub fn parse(s: &str) -> Result<Realtime, String> {
        let bad = |why: &str| format!("--realtime {s:?}: {why} (e.g. 250ms:! or 1.2s:0x91)");
        let (after_step, rest) = match s.strip_prefix('#') {
            Some(r) => {
                let (n, t) = r
                    .split_once('+')
                    .ok_or_else(|| bad("no time after the step"))?;
                (n.trim().parse().map_err(|_| bad("bad step number"))?, t)
            }
            None => (0, s),
        };
        let (time, what) = rest.split_once(':').ok_or_else(|| bad("no time"))?;
        let (num, scale) = match time.strip_suffix("ms") {
            Some(n) => (n, 1e3),
            None => (time.strip_suffix('s').unwrap_or(time), 1e6),
        };
        let v: f64 = num.trim().parse().map_err(|_| bad("bad time"))?;
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad("bad time"));
        }
        let mut bytes = Vec::new();
        for part in what.split(',') {
            let part = part.trim();
            let b = match part.strip_prefix("0x") {
                Some(h) => u8::from_str_radix(h, 16).map_err(|_| bad("bad hex byte"))?,
                None if part.len() == 1 => part.as_bytes()[0],
                None => return Err(bad("one character or 0xNN per byte")),
            };
            bytes.push(b);
        }
        Ok(Realtime {
            after_step,
            at_us: (v * scale).round() as u64,
            bytes,
        })
    }
}

/// As [`run_on`], calling `each_ms` with the board after every millisecond of virtual
/// time (for snapshots while a stream runs).
pub fn run_on_with(
    board: &mut Board,
    text: &str,
    flow: Flow,
    each_ms: &mut dyn FnMut(&mut Board),
) -> RunResult {
    run_on_timed(board, text, flow, &[], each_ms)
}

/// As [`run_on_with`], with real-time bytes sent at their times after the first step.
pub fn run_on_timed(
    board: &mut Board,
    text: &str,
    flow: Flow,
    realtime: &[Realtime],
    each_ms: &mut dyn FnMut(&mut Board),
) -> RunResult {
    let mut events = Vec::new();
    let mut r = run_on_each(
        board,
        text,
        flow,
        TIME_LIMIT_S,
        realtime,
        each_ms,
        &mut |e| events.push(e),
    );
    r.events = events;
    r
}

/// As [`run_on_timed`], handing each step event to `on_step` instead of keeping it
/// (the result's `events` stay empty), and giving up after `limit_s` of virtual
/// time: a long job's millions of steps need not be held, e.g. by the host's time
/// estimate, and a job of many hours can run to its end.
pub fn run_on_each(
    board: &mut Board,
    text: &str,
    flow: Flow,
    limit_s: u64,
    realtime: &[Realtime],
    each_ms: &mut dyn FnMut(&mut Board),
    on_step: &mut dyn FnMut(StepEvent),
) -> RunResult {
    let mut realtime: Vec<Realtime> = realtime.to_vec();
    realtime.sort_by_key(|r| (r.after_step, r.at_us));
    let mut rt_next = 0;
    let mut anchors: std::collections::BTreeMap<usize, Option<u64>> =
        realtime.iter().map(|r| (r.after_step, None)).collect();
    let mut steps_seen = 0usize;
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    let mut sender = Sender::new(flow);
    for (i, l) in lines.iter().enumerate() {
        sender.push(i, *l);
    }
    let (mut errors, mut alarms, mut messages) = (Vec::new(), Vec::new(), Vec::new());
    let mut received = |sender: &mut Sender<usize>, bytes: &[u8]| {
        for e in sender.received(bytes) {
            match e {
                Event::Answered(i, Answer::Error(n)) => errors.push(LineError {
                    line_no: i + 1,
                    text: lines[i].to_string(),
                    response: format!("error:{n}"),
                }),
                Event::Reply(Reply::Alarm(n)) => alarms.push(format!("ALARM:{n}")),
                Event::Reply(Reply::Feedback(m)) if m.starts_with("MSG:") => {
                    messages.push(format!("[{m}]"))
                }
                _ => {}
            }
        }
    };
    let mut unsent: Vec<u8> = Vec::new();
    let limit = board.now() + limit_s * TICK_HZ;
    let step = Board::ms_to_ticks(1);
    let mut timed_out = false;
    loop {
        // Bytes cross both ways until neither side has anything more to say; only then
        // does virtual time move on (USB latency is far below a step period).
        let out = board.usb_read();
        let mut progressed = !out.is_empty();
        received(&mut sender, &out);
        unsent.extend(sender.to_send());
        if !unsent.is_empty() {
            let n = board.usb_write(&unsent);
            unsent.drain(..n);
            progressed |= n > 0;
        }
        let out = board.usb_read();
        progressed |= !out.is_empty();
        received(&mut sender, &out);
        // Real-time bytes due (times from the first step).
        let due = |anchors: &std::collections::BTreeMap<usize, Option<u64>>, i: usize| {
            let r: &Realtime = realtime.get(i)?;
            let from = (*anchors.get(&r.after_step)?)?;
            Some(from + (r.at_us as u128 * u128::from(TICK_HZ) / 1_000_000) as u64)
        };
        while due(&anchors, rt_next).is_some_and(|t| t <= board.now()) {
            // Real-time bytes are taken as they arrive; the receive ring holds one
            // line at most with send-response, so they always fit.
            board.usb_write(&realtime[rt_next].bytes);
            board.wake_protocol();
            rt_next += 1;
            progressed = true;
        }
        if sender.done()
            && unsent.is_empty()
            && board.is_idle()
            && (rt_next >= realtime.len() || steps_seen == 0)
        {
            break;
        }
        if board.now() >= limit {
            timed_out = true;
            break;
        }
        if !progressed {
            let mut until = board.now() + step;
            let due_at = due(&anchors, rt_next);
            if let Some(t) = due_at {
                until = until.min(t.max(board.now() + 1));
            }
            let mut note = |e: StepEvent| {
                if let Some(at) = anchors.get_mut(&steps_seen) {
                    *at = Some(e.t);
                }
                steps_seen += 1;
                on_step(e)
            };
            if rt_next < realtime.len() && due_at.is_none() {
                // Its step has not come: stop at each step, to see whether it is the
                // one the byte is timed from.
                board.run_until_a_step(until, &mut note);
            } else {
                board.run_until(until, &mut note);
            }
            each_ms(board);
        }
    }
    RunResult {
        events: Vec::new(),
        first_motion: board.first_motion,
        errors,
        alarms,
        messages,
        lines: lines.len(),
        final_pos: board.pipeline.side().exec.position(),
        end: board.now(),
        timed_out,
        realtime_waiting: realtime
            .get(rt_next)
            .filter(|r| timed_out && r.after_step >= steps_seen)
            .map(|r| (r.after_step, steps_seen)),
        settings: board.ctl.protocol().machine().settings().clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A settings save between two moves (at rest, after the dwell's `ok`) programs
    /// the flash (half-word 52.5 µs each, the CPU stalled meanwhile) and costs the
    /// store's CPU work: both fall within the pipeline's resume wait (`RESUME_MS`),
    /// so the move after it starts at the same tick as without the save, on the
    /// simulator as on the board.
    #[test]
    fn a_settings_save_between_moves_falls_within_the_resume_wait() {
        let plain = run_gcode("G21 G91 G1 F600 X1\nG4 P0.01\nG1 X1\n", Flow::SendResponse);
        let saved = run_gcode(
            "G21 G91 G1 F600 X1\nG4 P0.01\n$110=2000\nG1 X1\n",
            Flow::SendResponse,
        );
        assert_eq!(saved.settings.max_rate(0), 2000.0, "saved");
        let times = |r: &RunResult| r.events.iter().map(|e| r.rel(e.t)).collect::<Vec<_>>();
        assert_eq!(times(&saved), times(&plain));
    }

    #[test]
    fn realtime_bytes_parse_and_a_timed_hold_lengthens_the_job_by_its_length() {
        assert_eq!(
            Realtime::parse("250ms:!").unwrap(),
            Realtime {
                after_step: 0,
                at_us: 250_000,
                bytes: vec![b'!']
            }
        );
        assert_eq!(
            Realtime::parse("1.5s:0x91,0x91").unwrap().bytes,
            [0x91, 0x91]
        );
        for bad in ["!", "xms:!", "1s:", "1s:0xZZ", "1s:ab", "-1s:!"] {
            assert!(Realtime::parse(bad).is_err(), "{bad}");
        }
        let prog = "G21 G91 G1 F600 X20\n";
        let plain = run_gcode(prog, Flow::SendResponse);
        let rt = [
            Realtime::parse("500ms:!").unwrap(),
            Realtime::parse("1500ms:~").unwrap(),
        ];
        let mut board = Board::new(Settings::default());
        let held = run_on_timed(&mut board, prog, Flow::SendResponse, &rt, &mut |_| {});
        let pos = |r: &RunResult| r.events.iter().map(|e| e.pos).collect::<Vec<_>>();
        assert_eq!(pos(&plain), pos(&held), "the same path");
        let longer = held.job_time_s() - plain.job_time_s();
        // Held for 1 s, less what the stop and the restart cost in ramps.
        assert!((0.8..1.2).contains(&longer), "{longer} s longer");
    }

    /// A resume timed from a step the held job never reaches leaves the hold waiting:
    /// the run says which byte, instead of only that it timed out.
    #[test]
    fn a_byte_timed_from_a_step_that_never_comes_is_named_at_the_time_out() {
        let rt = [
            Realtime::parse("#100+0ms:!").unwrap(),
            Realtime::parse("#5000+0ms:~").unwrap(),
        ];
        let mut board = Board::new(Settings::default());
        let r = run_on_each(
            &mut board,
            "G21 G91 G1 F600 X20\n",
            Flow::SendResponse,
            5,
            &rt,
            &mut |_| {},
            &mut |_| {},
        );
        assert!(r.timed_out);
        let (at, made) = r.realtime_waiting.expect("the resume is named");
        assert_eq!(at, 5000);
        assert!(
            (100..200).contains(&made),
            "{made} step events before the hold"
        );
    }

    #[test]
    fn a_square_runs_to_its_exact_corners() {
        let r = run_gcode(
            "G21 G90\nG1 X10 F3000\nG1 Y10\nG1 X0\nG1 Y0\n",
            Flow::SendResponse,
        );
        assert!(r.ok(), "{:?} {:?}", r.errors, r.alarms);
        assert_eq!(r.final_pos, [0, 0, 0]);
        // 40 mm of path at 80 steps/mm.
        assert_eq!(
            r.events.iter().map(|e| e.step.count_ones()).sum::<u32>(),
            3200
        );
        assert!(r.events.iter().any(|e| e.pos == [800, 800, 0]));
        assert!(
            r.job_time_s() > 0.8 && r.job_time_s() < 5.0,
            "{}",
            r.job_time_s()
        );
        assert_eq!(r.first_motion.map(|t| r.rel(t)), Some(0));
    }

    #[test]
    fn errors_and_alarms_are_reported_with_their_lines() {
        let r = run_gcode("G1 X1 F100\nG5 X2\nG1 Q3\n", Flow::SendResponse);
        let lines: Vec<usize> = r.errors.iter().map(|e| e.line_no).collect();
        assert_eq!(lines, [2, 3]);
        assert!(r.errors.iter().all(|e| e.response.starts_with("error:")));
        assert!(!r.ok());
    }

    #[test]
    fn drawings_follow_the_pen_of_either_kind() {
        let g = "G21 G90\nG0 X5\nM3\nG1 X10 F1200\nM5\nG0 X0 Y5\nM3\nG1 Y10\nM5\nG0 X0 Y0\n";
        for setup in ["", "$201=1\n"] {
            let r = run_gcode(&format!("{setup}{g}"), Flow::SendResponse);
            assert!(r.ok(), "{setup}: {:?} {:?}", r.errors, r.alarms);
            let d = r.drawing();
            let ends: Vec<_> = d
                .strokes
                .iter()
                .map(|s| (s[0], *s.last().unwrap()))
                .collect();
            assert_eq!(
                ends,
                [([5.0, 0.0], [10.0, 0.0]), ([0.0, 5.0], [0.0, 10.0])],
                "{setup}"
            );
            assert_eq!(d.travel.len(), 3, "{setup}: {:?}", d.travel);
        }
    }

    #[test]
    fn character_counting_gives_the_same_path() {
        let g = "G21 G90\nG1 X5 Y3 F2000\nG2 X5 Y3 I2 J0\nG1 X0 Y0\n";
        let a = run_gcode(g, Flow::SendResponse);
        let b = run_gcode(g, Flow::CharCount(128));
        assert!(a.ok() && b.ok());
        let pa: Vec<_> = a.events.iter().map(|e| e.pos).collect();
        let pb: Vec<_> = b.events.iter().map(|e| e.pos).collect();
        assert_eq!(pa, pb);
    }
}
