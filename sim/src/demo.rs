//! `cargo sim demo` and `--keys`: scripted standalone sessions on the virtual board.
//!
//! Owns the script player (key presses become row levels on the simulated matrix for
//! as long as they are held; waits let virtual time pass; LCD snapshots are written on
//! request) and the demo's storyline: boot, menu, the sine mode with its preview, the
//! sine being drawn, the five-pointed star, then a G-code program streamed over USB.
//! Everything the machine does comes from the core through the [`Board`].

use crate::board::{Board, StepEvent, TICK_HZ};
use crate::keys::{parse, Step, TAP_MS};
use crate::lcd;
use crate::render::Drawing;
use crate::run::run_on_with;
use crate::run::Flow;
use crate::trace::{Row, Trace};
use inkstep_core::settings::Settings;
use std::path::{Path, PathBuf};

/// The G-code part of the demo (a flower of arcs), shipped with the simulator.
pub const FLOWER: &str = include_str!("../demo/flower.nc");

/// The standalone part of the demo, in the `--keys` language (see [`crate::keys`]).
pub const DEMO_KEYS: &str = "\
    wait:400 lcd:01_boot wait:1400 lcd:02_menu \
    5 lcd:03_sine_form 10 enter 0.25 enter 0 enter 75.4 lcd:04_sine_length enter \
    wait:200 lcd:05_sine_preview enter wait:1500 lcd:06_sine_drawing idle wait:300 lcd:07_sine_done \
    back wait:200 6 30 enter wait:200 lcd:08_star_preview enter wait:2000 lcd:09_star_drawing \
    idle wait:300 lcd:10_star_done back wait:200 lcd:11_menu";

/// What a session produced.
pub struct Session {
    pub board: Board,
    pub events: Vec<StepEvent>,
    /// LCD snapshots written, in order.
    pub shots: Vec<PathBuf>,
    /// (what, first step tick, last step tick, steps) per part of the session.
    pub parts: Vec<(String, u64, u64, u64)>,
}

impl Session {
    pub fn new() -> Session {
        Session {
            board: Board::new(Settings::default()).with_lcd(),
            events: Vec::new(),
            shots: Vec::new(),
            parts: Vec::new(),
        }
    }

    fn run_for(&mut self, ms: u64) {
        let until = self.board.now() + Board::ms_to_ticks(ms);
        let ev = &mut self.events;
        self.board.run_until(until, &mut |e| ev.push(e));
    }

    /// Plays a `--keys` script, writing LCD snapshots into `out`.
    pub fn play(&mut self, script: &str, out: &Path) -> Result<(), String> {
        for step in parse(script)? {
            match step {
                Step::Press { key, ms } => {
                    self.board.held.push(key);
                    self.run_for(u64::from(ms));
                    self.board.held.retain(|k| *k != key);
                    self.run_for(u64::from(TAP_MS));
                }
                Step::Wait { ms } => self.run_for(u64::from(ms)),
                Step::Idle => {
                    let ev = &mut self.events;
                    if !self
                        .board
                        .run_to_idle(Board::ms_to_ticks(600_000), &mut |e| ev.push(e))
                    {
                        return Err(
                            "idle: the machine did not come to rest within 10 minutes".into()
                        );
                    }
                }
                Step::Lcd { name } => {
                    let path = snapshot(&mut self.board, &out.join(format!("{name}.png")))?;
                    self.shots.push(path);
                }
            }
        }
        Ok(())
    }

    /// Streams G-code over the simulated USB port, writing the LCD as `shot` (name in
    /// `out`) `shot_ms` after the stream starts; returns the sender's complaints.
    pub fn stream(
        &mut self,
        gcode: &str,
        shot: Option<(u64, &str, &Path)>,
    ) -> Result<Vec<String>, String> {
        let start = self.board.now();
        let mut pending = shot;
        let mut written: Option<Result<PathBuf, String>> = None;
        let r = run_on_with(&mut self.board, gcode, Flow::SendResponse, &mut |b| {
            if let Some((ms, name, out)) = pending {
                if b.now() >= start + Board::ms_to_ticks(ms) {
                    pending = None;
                    written = Some(snapshot(b, &out.join(format!("{name}.png"))));
                }
            }
        });
        if let Some(w) = written {
            self.shots.push(w?);
        }
        self.events.extend(r.events.iter().copied());
        let mut bad: Vec<String> = r
            .errors
            .iter()
            .map(|e| format!("line {}: {} -> {}", e.line_no, e.text, e.response))
            .collect();
        bad.extend(r.alarms);
        Ok(bad)
    }

    /// Marks the step events since `from` as one part of the session.
    pub fn part(&mut self, what: &str, from: usize) {
        let ev = &self.events[from.min(self.events.len())..];
        if let (Some(a), Some(b)) = (ev.first(), ev.last()) {
            let steps = ev.iter().map(|e| u64::from(e.step.count_ones())).sum();
            self.parts.push((what.to_string(), a.t, b.t, steps));
        }
    }

    /// Every step of the session as a trace (time from the session's start).
    pub fn trace(&self) -> Trace {
        Trace {
            rows: self
                .events
                .iter()
                .map(|e| Row {
                    t_us: e.t as f64 * 1e6 / TICK_HZ as f64,
                    pos: e.pos,
                })
                .collect(),
        }
    }

    /// The drawing of everything the pen put on paper.
    pub fn drawing(&self) -> Drawing {
        crate::run::drawing(&self.events, self.board.ctl.protocol().machine().settings())
    }
}

impl Default for Session {
    fn default() -> Self {
        Session::new()
    }
}

/// Refreshes the LCD and writes it to `path`.
pub fn snapshot(board: &mut Board, path: &Path) -> Result<PathBuf, String> {
    board.refresh_lcd();
    let fb = &board.lcd.as_ref().ok_or("the session has no LCD")?.fb;
    lcd::save_png(|x, y| fb.pixel(x, y), path)?;
    Ok(path.to_path_buf())
}

/// Writes the drawing as PNG and SVG into `out`.
pub fn write_drawing(s: &Session, out: &Path) -> Result<[PathBuf; 2], String> {
    let d = s.drawing();
    let png = out.join("drawing.png");
    let svg = out.join("drawing.svg");
    d.write_png(&png, 1000)?;
    std::fs::write(&svg, d.to_svg()).map_err(|e| format!("{}: {e}", svg.display()))?;
    Ok([png, svg])
}

/// The whole demo: keypad modes, then the G-code program; returns the session.
pub fn demo(out: &Path) -> Result<Session, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut s = Session::new();
    let mark = s.events.len();
    s.play(DEMO_KEYS, out)?;
    s.part("keypad: sine and star", mark);
    let mark = s.events.len();
    let bad = s.stream(FLOWER, Some((6000, "12_gcode_running", out)))?;
    if !bad.is_empty() {
        return Err(format!("the demo's G-code was refused: {}", bad.join("; ")));
    }
    s.part("G-code: flower", mark);
    s.play("wait:300 lcd:13_after_gcode", out)?;
    write_drawing(&s, out)?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use inkstep_core::hmi::MachineState;
    use inkstep_core::machine::MotionControl;

    #[test]
    fn abort_mid_drawing_stops_cleanly_where_the_pen_is() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = Session::new();
        // Star of 30 mm, then C (abort) one second into the drawing.
        s.play(
            "wait:1800 6 30 enter wait:200 enter wait:1000 back wait:1500",
            dir.path(),
        )
        .unwrap();
        let st = s.board.ctl.status(&s.board.pipeline);
        assert_eq!(st.state, MachineState::Idle, "{st:?}");
        assert!(s.board.pipeline.is_idle());
        assert!(s.board.is_idle());
        // The position is the executor's count, the last step of the trace.
        assert_eq!(st.pos, s.events.last().unwrap().pos);
        // It stopped part-way: the star's 142 mm were not all drawn.
        let steps: u32 = s.events.iter().map(|e| e.step.count_ones()).sum();
        assert!(steps > 100 && steps < 5000, "{steps}");
        // And the machine takes G-code afterwards, from where it is.
        let bad = s.stream("G91 G1 X5 F1200\n", None).unwrap();
        assert!(bad.is_empty(), "{bad:?}");
        let end = s.board.pipeline.side().exec.position();
        assert_eq!(end[0], st.pos[0] + 400);
    }
}
