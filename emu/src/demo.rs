//! `cargo emu demo` and `--keys`: the simulator's keypad scripts (the same `--keys`
//! language, `inkstep_sim::keys`) pressed on the emulated board's key matrix, and the
//! LCD written as PNGs from what the firmware sent the ST7920 over SPI2.
//!
//! A key press closes its row and column of the matrix for the time it is held; the
//! firmware scans and debounces it. `idle` asks `?` over USB until the answer is
//! `Idle`. `lcd:NAME` is the picture once the screen has caught up: the simulator
//! renders the state of the moment, the firmware redraws every 100 ms and then sends
//! the changed words, so the snapshot waits one refresh period, then until the LCD has
//! been drawn and its serial line has been quiet for a few milliseconds (a refresh
//! sends its words back to back). Each snapshot therefore lets up to ~0.2 s more pass
//! than the simulator's does; what is on the screen then is the same state.

use crate::clock::T_PER_MS;
use crate::session::Session;
use inkstep_serial::sender::Flow;
use inkstep_sim::keys::{matrix_pos, parse, Step, TAP_MS};
use std::path::{Path, PathBuf};

/// The firmware's LCD refresh period.
pub const LCD_REFRESH_MS: u64 = 100;
/// A serial line quiet this long means the refresh has been sent.
pub const QUIET_MS: u64 = 5;
/// Virtual time an `idle` or a snapshot may wait.
const LIMIT_MS: u64 = 600_000;

/// Run until the LCD shows what the firmware drew for the state of now (see the module
/// comment).
pub fn settle_lcd(s: &mut Session) -> Result<(), String> {
    s.run_for(LCD_REFRESH_MS * T_PER_MS)?;
    let limit = s.now() + LIMIT_MS * T_PER_MS;
    loop {
        if lcd_settled(s) {
            return Ok(());
        }
        if s.now() >= limit {
            return Err("the LCD never settled".into());
        }
        s.run_for(T_PER_MS)?;
    }
}

/// The LCD has been drawn and nothing is being sent to it.
fn lcd_settled(s: &Session) -> bool {
    let lcd = &s.m.state().board.lcd;
    lcd.showing() && s.now() >= lcd.last_byte_t + QUIET_MS * T_PER_MS
}

/// Write the LCD as `dir/NAME.png`.
pub fn save_lcd(s: &Session, dir: &Path, name: &str) -> Result<PathBuf, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let lcd = &s.m.state().board.lcd;
    let path = dir.join(format!("{name}.png"));
    inkstep_sim::lcd::save_png(|x, y| lcd.pixel(x, y), &path)?;
    Ok(path)
}

/// Hold `keys` (matrix positions) for `ms`.
fn hold(s: &mut Session, keys: Vec<(usize, usize)>, ms: u64) -> Result<(), String> {
    let mut o = s.m.state().board.outside.clone();
    o.keys = keys;
    s.set_outside(o);
    s.run_for(ms * T_PER_MS)
}

/// Play a `--keys` script; snapshots go to `out`. Returns the PNGs written.
pub fn play(s: &mut Session, script: &str, out: &Path) -> Result<Vec<PathBuf>, String> {
    let mut shots = Vec::new();
    for step in parse(script)? {
        match step {
            Step::Press { key, ms } => {
                hold(s, vec![matrix_pos(key)], u64::from(ms))?;
                hold(s, Vec::new(), u64::from(TAP_MS))?;
            }
            Step::Wait { ms } => s.run_for(u64::from(ms) * T_PER_MS)?,
            Step::Idle => {
                s.wait_idle(LIMIT_MS * T_PER_MS)?;
            }
            Step::Lcd { name } => {
                settle_lcd(s)?;
                shots.push(save_lcd(s, out, &name)?);
            }
        }
    }
    Ok(shots)
}

/// The simulator's whole demo on the emulated board: its keypad script, then its G-code
/// program (the flower) streamed over USB with a snapshot 6 s into it, then the screen
/// after it. Returns the PNGs written.
pub fn demo(s: &mut Session, out: &Path) -> Result<Vec<PathBuf>, String> {
    let mut shots = play(s, inkstep_sim::demo::DEMO_KEYS, out)?;
    s.boot()?;
    // The snapshot while streaming does not stop the sender: it is taken at the first
    // settled moment one refresh after the 6 s mark.
    let due = s.now() + (6000 + LCD_REFRESH_MS) * T_PER_MS;
    let mut shot = None;
    let streamed = s.stream(
        inkstep_sim::demo::FLOWER,
        Flow::SendResponse,
        LIMIT_MS * T_PER_MS,
        |s| {
            if shot.is_none() && s.now() >= due && lcd_settled(s) {
                shot = Some(save_lcd(s, out, "12_gcode_running")?);
            }
            Ok(())
        },
    )?;
    s.wait_idle(LIMIT_MS * T_PER_MS)?;
    shots.extend(shot);
    if !streamed.errors.is_empty() || !streamed.alarms.is_empty() {
        return Err(format!(
            "the demo's G-code was refused: {}",
            [streamed.errors, streamed.alarms].concat().join("; ")
        ));
    }
    shots.extend(play(s, "wait:300 lcd:13_after_gcode", out)?);
    Ok(shots)
}
