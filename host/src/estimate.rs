//! The time a job will take, from the firmware's own code: the program runs on
//! the simulator's virtual board (inkstep-sim: the core's interpreter, planner,
//! segment preparation and step executor, in virtual time) with the machine's
//! settings, and the time from its first motion to the end of the program (the
//! last line done, the machine at rest) is the job's time, pen lifts and drops
//! included. Nothing here models the planner: a
//! change to the firmware's motion changes the estimate with it.
//!
//! The settings come from the board (`$$` read over the port), from a file of
//! `$N=V` lines, or from flags; the program's own `$N=V` lines apply as it runs.
//! For the web view's progress, each move of the program (as the preview reads
//! it) also gets the time its end is reached, found in the step stream.

use crate::geom::Pt;
use crate::toolpath::Move;
use anyhow::{bail, Context, Result};
use inkstep_core::settings::Settings;
use inkstep_serial::grbl::{parse_reply, Reply};
use inkstep_serial::port::Transport;
use inkstep_sim::board::{Board, TICK_HZ};
use inkstep_sim::run::{run_on_each, Flow, LineError};
use std::time::{Duration, Instant};

/// The longest job estimated: a week of virtual time (about three minutes of
/// computing at the simulator's speed of an hour in 1.3 s).
pub const LIMIT_S: u64 = 7 * 24 * 3600;

/// What the virtual board made of a program.
#[derive(Clone, Debug, Default)]
pub struct Estimate {
    /// From the first motion to the end of the program (every line done and
    /// the machine at rest, as the board's own `Job finished` time counts it),
    /// seconds.
    pub job_s: f64,
    /// For each move asked about: seconds from the first motion to its end.
    pub ends_s: Vec<f64>,
    /// Lines the board refused, and alarms: the estimate covers the rest.
    pub errors: Vec<LineError>,
    pub alarms: Vec<String>,
    /// The job did not end within the simulator's hour.
    pub timed_out: bool,
}

impl Estimate {
    /// Warnings worth showing next to the time.
    pub fn warnings(&self) -> Vec<String> {
        let mut w: Vec<String> = self
            .errors
            .iter()
            .take(5)
            .map(|e| format!("line {}: {} on `{}`", e.line_no, e.response, e.text))
            .collect();
        if self.errors.len() > 5 {
            w.push(format!("and {} more refused lines", self.errors.len() - 5));
        }
        w.extend(self.alarms.iter().cloned());
        if self.timed_out {
            w.push("the job did not end within a week: estimate stopped there".into());
        }
        w
    }
}

/// Settings from `$N=V` lines (the firmware's defaults for the rest); other
/// lines (`ok`, blanks, comments in parentheses) are skipped.
pub fn settings_from_text(text: &str) -> Result<Settings> {
    let mut s = Settings::default();
    for (k, l) in text.lines().enumerate() {
        if let Reply::Setting(n, v) = parse_reply(l) {
            let v: f32 = v
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("line {}: `{}` is not a number", k + 1, v))?;
            s.set(n, v)
                .map_err(|e| anyhow::anyhow!("line {}: ${n}={v}: {e:?}", k + 1))?;
        }
    }
    Ok(s)
}

/// Applies "N=V" flags (e.g. `110=5000`) to `s`.
pub fn apply_flags(s: &mut Settings, flags: &[String]) -> Result<()> {
    for f in flags {
        let (n, v) = f
            .trim_start_matches('$')
            .split_once('=')
            .with_context(|| format!("--set {f}: expected N=V"))?;
        let n: u16 = n.trim().parse().with_context(|| format!("--set {f}"))?;
        let v: f32 = v.trim().parse().with_context(|| format!("--set {f}"))?;
        s.set(n, v)
            .map_err(|e| anyhow::anyhow!("--set {f}: {e:?}"))?;
    }
    Ok(())
}

/// The board's settings, asked with `$$` (waits at most 3 s for the listing's
/// `ok`; everything received up to it is consumed, so a stream can follow).
pub fn read_settings<T: Transport>(t: &mut T) -> Result<Settings> {
    t.send(b"$$\n")?;
    let t0 = Instant::now();
    let (mut text, mut pending) = (String::new(), Vec::new());
    let mut buf = [0u8; 512];
    while t0.elapsed() < Duration::from_secs(3) {
        let n = t.recv(&mut buf)?;
        pending.extend_from_slice(&buf[..n]);
        while let Some(i) = pending.iter().position(|&b| b == b'\n') {
            let line: Vec<u8> = pending.drain(..=i).collect();
            let line = String::from_utf8_lossy(&line).trim().to_string();
            match parse_reply(&line) {
                Reply::Ok => return settings_from_text(&text),
                Reply::Error(n) => bail!("$$ answered error:{n}"),
                Reply::Setting(..) => {
                    text.push_str(&line);
                    text.push('\n');
                }
                _ => {}
            }
        }
    }
    bail!("no answer to $$ within 3 s")
}

/// Runs `program` on a virtual board with settings `s`, the pen starting at
/// `start` (work = machine coordinates, as on a board at its origin), and
/// times it; `moves` (the program's moves, in order) get their end times.
pub fn estimate(program: &str, s: &Settings, start: Pt, moves: &[Move]) -> Estimate {
    let mut board = Board::new(s.clone());
    let flow = Flow::CharCount(inkstep_core::protocol::RX_BUFFER_SIZE);
    if start != Pt::new(0.0, 0.0) {
        let go = format!("G21G90G0X{:.4}Y{:.4}\n", start.x, start.y);
        run_on_each(&mut board, &go, flow, 60, &[], &mut |_| {}, &mut |_| {});
        board.first_motion = None;
    }
    let spmm = [s.steps_per_mm(0) as f64, s.steps_per_mm(1) as f64];
    let targets: Vec<[i64; 2]> = moves
        .iter()
        .map(|m| {
            [
                (m.to.x * spmm[0]).round() as i64,
                (m.to.y * spmm[1]).round() as i64,
            ]
        })
        .collect();
    let mut reached: Vec<u64> = Vec::with_capacity(moves.len());
    let mut last = None;
    let r = run_on_each(
        &mut board,
        program,
        flow,
        LIMIT_S,
        &[],
        // An M0 pause or an M6 pen change waits for the user: the estimate is the
        // machine's time, so cycle start is pressed at once (the user's time is theirs).
        &mut |b| {
            if b.ctl.protocol().machine().prompt().is_some() {
                b.usb_write(b"~");
                b.wake_protocol();
            }
        },
        &mut |e| {
            last = Some(e.t);
            let (x, y) = (i64::from(e.pos[0]), i64::from(e.pos[1]));
            while let Some(t) = targets.get(reached.len()) {
                if (t[0] - x).abs() <= 1 && (t[1] - y).abs() <= 1 {
                    reached.push(e.t);
                } else {
                    break;
                }
            }
        },
    );
    let t0 = r.first_motion.unwrap_or(0);
    let secs = |t: u64| t.saturating_sub(t0) as f64 / TICK_HZ as f64;
    // Lines after the last motion (dwells, M2) take time too.
    let job_s = if last.is_some() { secs(r.end) } else { 0.0 };
    let mut ends_s: Vec<f64> = reached.iter().map(|&t| secs(t)).collect();
    // Moves never reached (a program with offsets the preview does not apply,
    // a refused line): the rest of the time shared by their lengths.
    if ends_s.len() < moves.len() {
        let from = ends_s.last().copied().unwrap_or(0.0);
        let rest = &moves[ends_s.len()..];
        let total: f64 = rest.iter().map(|m| m.from.dist(m.to)).sum();
        let mut acc = 0.0;
        for m in rest {
            acc += m.from.dist(m.to);
            let f = if total > 0.0 { acc / total } else { 1.0 };
            ends_s.push(from + f * (job_s - from).max(0.0));
        }
    }
    Estimate {
        job_s,
        ends_s,
        errors: r.errors,
        alarms: r.alarms,
        timed_out: r.timed_out,
    }
}

/// "1:02:03", "4:05" or "7.3 s".
pub fn fmt_time(s: f64) -> String {
    if s < 60.0 {
        return format!("{s:.1} s");
    }
    let t = s.round() as u64;
    let (h, m, sec) = (t / 3600, t / 60 % 60, t % 60);
    if h > 0 {
        format!("{h}:{m:02}:{sec:02}")
    } else {
        format!("{m}:{sec:02}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath;

    #[test]
    fn the_estimate_is_the_boards_time_with_its_settings() {
        let g = "G21 G90\nG0 X10\nM3\nG1 X10 Y10 F600\nM5\nG0 X0 Y0\n";
        let moves = toolpath::parse(g).unwrap();
        let s = Settings::default();
        let e = estimate(g, &s, Pt::new(0.0, 0.0), &moves);
        // The same program on a board with the same settings, timed by the simulator
        // to its last step; the estimate runs to the end of the program: the tick
        // that sees the machine at rest, 0.4 to 1.4 ms after the last step.
        let r = inkstep_sim::run::run_gcode(g, Flow::CharCount(128));
        assert!(
            (e.job_s - r.job_time_s()).abs() < 1.5e-3,
            "{} {}",
            e.job_s,
            r.job_time_s()
        );
        // Each move's end in order; the draw takes 1 s at 600 mm/min and more
        // with its pen drop and acceleration.
        assert_eq!(e.ends_s.len(), 3);
        assert!(e.ends_s.windows(2).all(|w| w[0] <= w[1]));
        let draw = e.ends_s[1] - e.ends_s[0];
        assert!(draw > 1.0 && draw < 2.0, "{draw}");
        // Slower acceleration, longer job; a servo pen waits its $204.
        let mut slow = s.clone();
        apply_flags(&mut slow, &["120=20".into(), "121=20".into()]).unwrap();
        assert!(estimate(g, &slow, Pt::new(0.0, 0.0), &moves).job_s > e.job_s + 0.5);
        let servo = settings_from_text("$201=1\n$204=500\nok\n").unwrap();
        let sv = estimate(g, &servo, Pt::new(0.0, 0.0), &moves);
        assert!(sv.job_s > 2.0, "{}", sv.job_s);
        assert!(apply_flags(&mut slow, &["nonsense".into()]).is_err());
        assert!(settings_from_text("$110=fast\n").is_err());
    }

    /// A job with pen changes (an SVG's layers) and an M0 pause ends: the waits for the
    /// user cost nothing, the pen's lift and drop around each change are counted.
    #[test]
    fn pen_changes_and_pauses_do_not_stop_the_estimate() {
        let plain = "G21 G90\nM3\nG1 X10 F600\nM5\nM3\nG1 X20\nM5\n";
        let changes = "G21 G90\nM3\nG1 X10 F600\nM5\n(MSG,pen 2: red)\nM6 T2\nM0\nM3\nG1 X20\nM5\n";
        let s = settings_from_text("$201=1\n$204=200\nok\n").unwrap();
        let est = |g: &str| {
            let moves = toolpath::parse(g).unwrap();
            estimate(g, &s, Pt::new(0.0, 0.0), &moves)
        };
        let (a, b) = (est(plain), est(changes));
        assert!(!b.timed_out && b.errors.is_empty(), "{:?}", b.errors);
        // The change lifts and drops the pen once more at most: within the pen's times.
        assert!(
            b.job_s >= a.job_s - 1e-3 && b.job_s < a.job_s + 1.0,
            "{} {}",
            a.job_s,
            b.job_s
        );
    }

    #[test]
    fn times_read_well() {
        assert_eq!(fmt_time(7.34), "7.3 s");
        assert_eq!(fmt_time(65.0), "1:05");
        assert_eq!(fmt_time(3723.0), "1:02:03");
    }
}
