//! Resuming a job after a stop, an alarm or a power cut: which line to resume
//! from, and the lines that bring a board that has forgotten everything (a soft
//! reset clears G92, the feed, the pen; a power cut also the position) back to
//! the state the job had when that line started.
//!
//! The state is rebuilt by the firmware's own interpreter (inkstep-core's
//! [`Interpreter`]), run over the skipped lines with the board's settings: units,
//! distance and feed modes, the work coordinate system, G92 and tool length
//! offsets, the feed, the S value, the pen and the motion mode come out of it
//! exactly as the board would have them, and the position where the line starts.
//! The preamble written from that state is read back by a fresh interpreter and
//! must give the same state, or resuming is refused: a wrong preamble would draw
//! in the wrong place. Settings lines (`$N=V`) among the skipped ones are sent
//! again (they are idempotent, and a fresh board may not have them); the stored
//! coordinate systems (G10, G28.1, G30.1) live in the board's flash and are not
//! written again.
//!
//! Where to resume comes from what the host saw: the line the board reported
//! drawing (`Ln:` of the status report, for lines with N numbers), or else the
//! line whose motion passes through the last position the board reported,
//! searched among the lines that can still have been in its planner. The line
//! is remembered in a small state file so that `send --resume` needs no number.

use crate::geom::Pt;
use crate::toolpath::arc_points;
use anyhow::{bail, Context, Result};
use inkstep_core::gcode::interpreter::Interpreter;
use inkstep_core::gcode::modal::{Modal, MotionMode};
use inkstep_core::gcode::units::NmPos;
use inkstep_core::planner::PLANNER_BLOCKS;
use inkstep_core::settings::{PenMode, Settings};
use inkstep_serial::stream::{prepare, Line};
use std::path::{Path, PathBuf};

/// Where each sendable line of a program starts and ends (work coordinates,
/// mm) and its N number, as the firmware's interpreter reads the program.
#[derive(Clone, Debug, PartialEq)]
pub struct Span {
    pub file_line: usize,
    pub from: [f64; 3],
    pub to: [f64; 3],
    /// The line's N word, if it has one.
    pub n: Option<u32>,
    /// Points along the way of an arc (G2/G3), within 5 µm of it; empty for
    /// a straight move.
    pub via: Vec<[f64; 3]>,
}

impl Span {
    /// The line moves the pen.
    pub fn moves(&self) -> bool {
        self.from != self.to || !self.via.is_empty()
    }

    /// Distance from `p` to the line's motion.
    pub fn dist(&self, p: [f64; 3]) -> f64 {
        let mut best = f64::INFINITY;
        let mut a = self.from;
        for &b in self.via.iter().chain(std::iter::once(&self.to)) {
            best = best.min(dist(p, a, b));
            a = b;
        }
        best
    }
}

/// The points along an arc line (`b`: the interpreter after it) from `from`
/// to `to`, or none for any other line.
fn arc_via(text: &str, b: &Interpreter, from: [f64; 3], to: [f64; 3]) -> Vec<[f64; 3]> {
    let cw = match b.modal().motion {
        MotionMode::ArcCw => true,
        MotionMode::ArcCcw => false,
        _ => return Vec::new(),
    };
    // Only a line with an arc's words is an arc (a refused line, or one
    // without motion, leaves the mode as it was).
    let Ok(blk) = inkstep_core::gcode::parser::WordBlock::parse(text.as_bytes()) else {
        return Vec::new();
    };
    if !(blk.get(b'I').is_some() || blk.get(b'J').is_some() || blk.get(b'R').is_some()) {
        return Vec::new();
    }
    let scale = if b.modal().inches { 25.4 } else { 1.0 };
    let v = |c: u8| blk.get(c).map(|v| v.millionths() as f64 / 1e6 * scale);
    let (f, t) = (Pt::new(from[0], from[1]), Pt::new(to[0], to[1]));
    let Ok(pts) = arc_points(
        f,
        t,
        v(b'I').unwrap_or(0.0),
        v(b'J').unwrap_or(0.0),
        v(b'R'),
        cw,
        0.005,
    ) else {
        return Vec::new();
    };
    let n = pts.len().max(1) as f64;
    pts.iter()
        .enumerate()
        .take(pts.len().saturating_sub(1))
        .map(|(k, q)| [q.x, q.y, from[2] + (to[2] - from[2]) * (k + 1) as f64 / n])
        .collect()
}

/// The sendable lines of a program (cleaned as the sender cleans them) and
/// settings with the program's own `$N=V` lines applied as they come.
fn lines_of(program: &str) -> Result<Vec<Line>> {
    prepare(program, 128).map_err(anyhow::Error::msg)
}

/// `$N=V` of a cleaned line.
fn setting_of(text: &str) -> Option<(u16, f32)> {
    let (n, v) = text.strip_prefix('$')?.split_once('=')?;
    Some((n.parse().ok()?, v.parse().ok()?))
}

/// The N word a cleaned line starts with.
pub fn n_word(text: &str) -> Option<u32> {
    let rest = text.strip_prefix('N')?;
    let end = rest
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(rest.len());
    rest[..end].parse().ok()
}

fn nm_to_mm(nm: i64) -> f64 {
    nm as f64 / 1e6
}

fn work_mm(i: &Interpreter) -> [f64; 3] {
    let (p, o) = (i.position(), i.work_offset());
    [0, 1, 2].map(|k| nm_to_mm(p[k].saturating_sub(o[k])))
}

/// Runs the interpreter over `lines`, applying settings lines to `s`; a line
/// the interpreter refuses changes nothing (as on the board). Calls `each`
/// with every line and the interpreter before and after it.
fn interpret(
    lines: &[Line],
    s: &mut Settings,
    mut each: impl FnMut(&Line, &Interpreter, &Interpreter),
) -> Interpreter {
    let mut it = Interpreter::new();
    for l in lines {
        let before = it.clone();
        if l.text.starts_with('$') {
            if let Some((n, v)) = setting_of(&l.text) {
                let _ = s.set(n, v);
            }
        } else {
            let _ = it.execute(l.text.as_bytes(), s, l.file_line as u32);
        }
        each(l, &before, &it);
    }
    it
}

/// Each sendable line's span, from the board's settings `s`.
pub fn spans(program: &str, s: &Settings) -> Result<Vec<Span>> {
    Ok(spans_of(&lines_of(program)?, s))
}

/// [`spans`] of lines as they are sent (a resumed job's preamble included).
pub fn spans_of(lines: &[Line], s: &Settings) -> Vec<Span> {
    let mut s = s.clone();
    let mut out = Vec::with_capacity(lines.len());
    interpret(lines, &mut s, |l, a, b| {
        let (from, to) = (work_mm(a), work_mm(b));
        out.push(Span {
            file_line: l.file_line,
            from,
            to,
            n: n_word(&l.text),
            via: arc_via(&l.text, b, from, to),
        })
    });
    out
}

/// A length in nanometres as exact decimal millimetres ("-12.5", "0.0125").
fn mm(nm: i64) -> String {
    let sign = if nm < 0 { "-" } else { "" };
    let a = nm.unsigned_abs();
    let (whole, frac) = (a / 1_000_000, a % 1_000_000);
    if frac == 0 {
        format!("{sign}{whole}")
    } else {
        let f = format!("{frac:06}");
        format!("{sign}{whole}.{}", f.trim_end_matches('0'))
    }
}

fn num(v: f32) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// What a resumed program must restore, compared after reading the preamble.
fn state(i: &Interpreter) -> (Modal, f32, f32, NmPos, i64, [i64; 3]) {
    let (p, o) = (i.position(), i.work_offset());
    (
        *i.modal(),
        if i.modal().inverse_time {
            0.0
        } else {
            i.feed()
        },
        i.spindle(),
        *i.g92(),
        i.tool_length_offset(),
        [0, 1, 2].map(|k| p[k].saturating_sub(o[k])),
    )
}

/// The program to send to resume `program` at file line `from_line` (1-based)
/// on a board with settings `s`: the preamble that rebuilds the state (pen
/// up, travel to where the line starts, pen down if it was), then the lines
/// from `from_line` on. Preamble lines carry `from_line` as their file line.
pub fn resume_lines(program: &str, from_line: usize, s: &Settings) -> Result<Vec<Line>> {
    resume_lines_of(&lines_of(program)?, from_line, s)
}

/// [`resume_lines`] of a program already prepared for sending.
pub fn resume_lines_of(lines: &[Line], from_line: usize, s: &Settings) -> Result<Vec<Line>> {
    let k = lines.partition_point(|l| l.file_line < from_line);
    if k >= lines.len() {
        bail!("nothing to resume from line {from_line}: the program has no line to send there");
    }
    let (skipped, rest) = lines.split_at(k);
    let mut s = s.clone();
    let mut settings_lines = Vec::new();
    let mut zmax = f64::NEG_INFINITY;
    let target = interpret(skipped, &mut s, |l, _, it| {
        if setting_of(&l.text).is_some() {
            settings_lines.push(l.text.clone());
        }
        zmax = zmax.max(work_mm(it)[2]);
    });
    let m = *target.modal();
    let (p, wo, g92, tlo) = (
        *target.position(),
        target.work_offset(),
        *target.g92(),
        target.tool_length_offset(),
    );
    // The work coordinate system's own offset (without G92 and the tool offset).
    let wcs = target
        .coords()
        .wcs
        .get(usize::from(m.wcs))
        .copied()
        .unwrap_or([0; 3]);
    let frame = [p[0].saturating_sub(wcs[0]), p[1].saturating_sub(wcs[1])];
    let work = [0, 1, 2].map(|a| p[a].saturating_sub(wo[a]));

    let mut pre: Vec<String> = settings_lines;
    pre.push(format!("G92.1G49G21G90G94G17G{}", 54 + m.wcs));
    pre.push("M5".into());
    let mut check = Interpreter::new();
    check.set_coords(*target.coords());
    let run = |check: &mut Interpreter, pre: &[String]| -> Result<()> {
        for l in pre {
            if !l.starts_with('$') {
                check
                    .execute(l.as_bytes(), &s, from_line as u32)
                    .map_err(|e| anyhow::anyhow!("resume line `{l}` refused: {e:?}"))?;
            }
        }
        Ok(())
    };
    run(&mut check, &pre)?;
    // The pen up before the travel: M5 moves a Z pen only when the board
    // thinks it down, and after a reset it thinks it up wherever it is, so
    // Z goes to the up height ($205) itself; and above everything the job
    // drew at if the program moves Z itself.
    let mut z_safe = if zmax.is_finite() {
        mm_nm(zmax).saturating_add(wo[2]).saturating_sub(wcs[2])
    } else {
        i64::MIN
    };
    if s.pen_mode() == PenMode::ZAxis {
        z_safe = z_safe.max(mm_nm(f64::from(s.pen_z_up())).saturating_sub(wcs[2]));
    }
    if z_safe > i64::MIN {
        pre.push(format!("G0Z{}", mm(z_safe)));
    }
    pre.push(format!("G0X{}Y{}", mm(frame[0]), mm(frame[1])));
    if tlo != 0 {
        pre.push(format!("G43.1Z{}", mm(tlo)));
    }
    if m.pen_down {
        pre.push(if target.spindle() > 0.0 {
            format!("M3S{}", num(target.spindle()))
        } else {
            "M3".into()
        });
    } else if target.spindle() > 0.0 {
        pre.push(format!("S{}", num(target.spindle())));
    }
    // Z where the line starts (a Z pen lowered by M3 is there already).
    let mut c = Interpreter::new();
    c.set_coords(*target.coords());
    run(&mut c, &pre)?;
    if c.position()[2] != p[2] {
        pre.push(format!("G0Z{}", mm(p[2] - wcs[2] - tlo)));
    }
    if g92 != [0; 3] {
        pre.push(format!(
            "G92X{}Y{}Z{}",
            mm(work[0]),
            mm(work[1]),
            mm(work[2])
        ));
    }
    if target.feed() > 0.0 && !m.inverse_time {
        pre.push(format!("F{}", num(target.feed())));
    }
    let mut modes = String::new();
    if m.inches {
        modes += "G20";
    }
    if m.incremental {
        modes += "G91";
    }
    if m.inverse_time {
        modes += "G93";
    }
    // An arc mode cannot be set without an arc: the first line that moves
    // gets the G2/G3 word instead (when it names no motion of its own).
    let arc = match m.motion {
        MotionMode::ArcCw => Some("G2"),
        MotionMode::ArcCcw => Some("G3"),
        _ => None,
    };
    modes += match m.motion {
        MotionMode::Rapid => "G0",
        MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw => "G1",
        MotionMode::Cancel => "G80",
    };
    pre.push(modes);
    // Read back: the preamble must leave the board as the skipped lines did.
    let mut c = Interpreter::new();
    c.set_coords(*target.coords());
    run(&mut c, &pre).context("the resume preamble does not read back")?;
    let mut got = state(&c);
    if arc.is_some() {
        got.0.motion = m.motion;
    }
    if got != state(&target) {
        bail!(
            "cannot rebuild the state before line {from_line}: the preamble gives {got:?}, \
             the job had {:?}",
            state(&target)
        );
    }
    let mut out: Vec<Line> = pre
        .into_iter()
        .map(|text| Line {
            file_line: from_line,
            text,
        })
        .collect();
    out.extend_from_slice(rest);
    if let Some(g) = arc {
        let first = out.len() - rest.len();
        let moving = out[first..].iter_mut().find(|l| {
            inkstep_core::gcode::parser::WordBlock::parse(l.text.as_bytes()).is_ok_and(|b| {
                b.get(b'X').is_some() || b.get(b'Y').is_some() || b.get(b'Z').is_some()
            })
        });
        if let Some(l) = moving {
            let b = inkstep_core::gcode::parser::WordBlock::parse(l.text.as_bytes());
            let own = b.is_ok_and(|b| b.g.iter().any(|&c| matches!(c, 0 | 10 | 20 | 30 | 800)));
            if !own {
                l.text = format!("{g}{}", l.text);
            }
        }
    }
    Ok(out)
}

fn mm_nm(mm: f64) -> i64 {
    (mm * 1e6).round() as i64
}

/// What the host saw of a job that stopped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Seen {
    /// The last `Ln:` the board reported.
    pub ln: Option<u32>,
    /// The last work position the board reported (mm).
    pub pos: Option<[f64; 3]>,
    /// Lines (of the prepared program, in order) answered `ok`.
    pub acked: usize,
    /// Lines sent.
    pub sent: usize,
}

/// Distance from `p` to the segment `a`-`b`.
fn dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1] + (p[2] - a[2]) * d[2]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = [a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]];
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// A position within this of a line's motion is on it (mm): a step of a
/// fine machine is 0.0125 mm.
const ON_LINE_MM: f64 = 0.02;

/// The file line to resume from, given the program's spans and what the host
/// saw: the line `Ln:` named; or the earliest line, among those that can still
/// have been in the board's planner, whose motion passes through the last
/// reported position (else the nearest); or, knowing neither, the first line
/// not answered. None when every line was answered and nothing is known.
pub fn resume_point(spans: &[Span], seen: &Seen) -> Option<usize> {
    if let Some(n) = seen.ln {
        // The last line with that number that was sent (numbers may repeat).
        if let Some(s) = spans[..seen.sent.min(spans.len())]
            .iter()
            .rev()
            .find(|s| s.n == Some(n))
        {
            return Some(s.file_line);
        }
    }
    let hi = seen.sent.min(spans.len());
    // Lines that move, answered: the planner holds at most PLANNER_BLOCKS of
    // them (an arc's line holds several), and one more waits to enter it.
    let mut lo = seen.acked.min(hi);
    let mut moving = 0;
    while lo > 0 && moving <= PLANNER_BLOCKS + 2 {
        lo -= 1;
        if spans[lo].moves() {
            moving += 1;
        }
    }
    let Some(p) = seen.pos else {
        return spans.get(seen.acked).map(|s| s.file_line);
    };
    let window = &spans[lo..hi];
    let on = window.iter().find(|s| s.moves() && s.dist(p) <= ON_LINE_MM);
    let pick = on.or_else(|| {
        window
            .iter()
            .filter(|s| s.moves())
            .min_by(|a, b| a.dist(p).total_cmp(&b.dist(p)))
    });
    pick.map(|s| s.file_line)
        .or_else(|| spans.get(seen.acked).map(|s| s.file_line))
}

/// The resume state file: one line per job, `LINE<TAB>PATH`, kept in the
/// user's cache folder ($XDG_CACHE_HOME or ~/.cache, inkstep/resume.tsv), or
/// where $INKSTEP_STATE_DIR says.
pub fn state_file() -> Option<PathBuf> {
    let dir = std::env::var_os("INKSTEP_STATE_DIR")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("XDG_CACHE_HOME").map(|d| PathBuf::from(d).join("inkstep")))
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/inkstep")))?;
    Some(dir.join("resume.tsv"))
}

fn job_key(job: &Path) -> String {
    std::fs::canonicalize(job)
        .unwrap_or_else(|_| job.to_path_buf())
        .display()
        .to_string()
}

fn read_state(f: &Path) -> Vec<(usize, String)> {
    std::fs::read_to_string(f)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| {
            let (n, p) = l.split_once('\t')?;
            Some((n.parse().ok()?, p.to_string()))
        })
        .collect()
}

/// Remembers (Some) or forgets (None) where `job` stopped.
pub fn remember(job: &Path, line: Option<usize>) -> Result<()> {
    let Some(f) = state_file() else {
        return Ok(());
    };
    let key = job_key(job);
    let mut all: Vec<(usize, String)> = read_state(&f)
        .into_iter()
        .filter(|(_, p)| *p != key)
        .collect();
    if let Some(n) = line {
        all.push((n, key));
    }
    if let Some(d) = f.parent() {
        std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    let text: String = all.iter().map(|(n, p)| format!("{n}\t{p}\n")).collect();
    std::fs::write(&f, text).with_context(|| format!("writing {}", f.display()))
}

/// Where `job` stopped last, if remembered.
pub fn remembered(job: &Path) -> Option<usize> {
    let key = job_key(job);
    read_state(&state_file()?)
        .into_iter()
        .find(|(_, p)| *p == key)
        .map(|(n, _)| n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(l: &[Line]) -> Vec<&str> {
        l.iter().map(|l| l.text.as_str()).collect()
    }

    #[test]
    fn the_preamble_rebuilds_units_offsets_feed_and_pen() {
        let s = Settings::default();
        let g = "G21 G90\nG92 X5 Y5\nG1 X10 Y10 F1200\nM3 S500\nG91 G1 X1\nG20\nX0.1\nY0.1\n";
        let r = resume_lines(g, 7, &s).unwrap();
        let t = texts(&r);
        // Line 7 ("X0.1") and the rest follow the preamble as they are.
        assert_eq!(&t[t.len() - 2..], ["X0.1", "Y0.1"]);
        // The pen is lifted before the travel and dropped after it, the travel
        // goes to where line 7 starts in the frame without G92 (11-5, 10-5),
        // and G92 makes that the job's 11,10 again.
        let pre = &t[..t.len() - 2];
        let up = pre.iter().position(|l| *l == "M5").unwrap();
        let go = pre.iter().position(|l| *l == "G0X6Y5").unwrap();
        let down = pre.iter().position(|l| l.starts_with("M3S500")).unwrap();
        assert!(up < go && go < down, "{pre:?}");
        assert!(pre.iter().any(|l| l.starts_with("G92X11Y10Z")), "{pre:?}");
        assert!(pre.contains(&"F1200"), "{pre:?}");
        assert_eq!(pre.last(), Some(&"G20G91G1"));
        // Every line carries the line resumed.
        assert!(r[..pre.len()].iter().all(|l| l.file_line == 7));
        assert!(resume_lines(g, 9, &s).is_err());
    }

    #[test]
    fn settings_lines_are_sent_again_and_a_z_pen_is_raised_first() {
        let g = "$100=100\nG90\nG0 Z5\nG0 X10\nG1 Z0 F300\nG1 X20 F1000\nG1 Y20\n";
        let r = resume_lines(g, 7, &Settings::default()).unwrap();
        let t = texts(&r);
        assert_eq!(t[0], "$100=100");
        let z_up = t.iter().position(|l| *l == "G0Z5").unwrap();
        let go = t.iter().position(|l| *l == "G0X20Y0").unwrap();
        let z_down = t.iter().position(|l| *l == "G0Z0").unwrap();
        assert!(z_up < go && go < z_down, "{t:?}");
        assert_eq!(t.last(), Some(&"G1Y20"));
    }

    #[test]
    fn the_resume_point_is_the_line_drawing_at_the_reported_position() {
        let g = "G90\nG0 X10\nM3\nG1 X20 F1000\nG1 X20 Y10\nG1 X10 Y10\nM5\nG0 X0 Y0\n";
        let sp = spans(g, &Settings::default()).unwrap();
        let all = sp.len();
        let seen = |pos, acked| Seen {
            ln: None,
            pos: Some(pos),
            acked,
            sent: all,
        };
        assert_eq!(resume_point(&sp, &seen([20.0, 4.0, 0.0], all)), Some(5));
        // Where two lines meet, the earlier: nothing is drawn twice.
        assert_eq!(resume_point(&sp, &seen([20.0, 0.0, 0.0], all)), Some(4));
        // Ln: names the line, by its N number.
        let numbered = "N10 G90\nN20 G0 X10\nN30 G1 X20 F1000\nN40 G1 Y10\n";
        let sp = spans(numbered, &Settings::default()).unwrap();
        let s = Seen {
            ln: Some(30),
            pos: Some([0.0; 3]),
            acked: 4,
            sent: 4,
        };
        assert_eq!(resume_point(&sp, &s), Some(3));
    }

    #[test]
    fn an_arc_in_modal_g2_resumes() {
        let g = "G21 G90\nG2 X10 Y0 I5 J0 F500\nX0 Y0 I-5 J0\n";
        let r = resume_lines(g, 3, &Settings::default()).unwrap();
        let t = texts(&r);
        // The arc mode rides on the arc's own line.
        assert!(
            t.contains(&"G0X10Y0") && t.last() == Some(&"G2X0Y0I-5J0"),
            "{t:?}"
        );
    }

    #[test]
    fn the_state_file_remembers_each_job() {
        let dir = std::env::temp_dir().join(format!("inkstep-resume-{}", std::process::id()));
        std::env::set_var("INKSTEP_STATE_DIR", &dir);
        let (a, b) = (dir.join("a.nc"), dir.join("b.nc"));
        remember(&a, Some(12)).unwrap();
        remember(&b, Some(40)).unwrap();
        remember(&a, Some(15)).unwrap();
        assert_eq!((remembered(&a), remembered(&b)), (Some(15), Some(40)));
        remember(&a, None).unwrap();
        assert_eq!((remembered(&a), remembered(&b)), (None, Some(40)));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
