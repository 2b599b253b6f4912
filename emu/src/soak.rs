//! The soak: the board streamed G-code over USB for minutes of virtual time with the
//! LCD running, as a sender drives it (the reference programs one after the other,
//! `?` every 100 ms), and the watchdog must never fire. `cargo emu soak --minutes N`
//! runs it; the fault tests run it for 2 minutes.

use crate::clock::{T_PER_MS, T_PER_S};
use crate::session::Session;
use inkstep_serial::sender::Flow;

/// The reference programs streamed in turn (each ends where its G-code says).
pub const PROGRAMS: [(&str, &str); 4] = [
    ("star.nc", include_str!("../../bench/star.nc")),
    ("circle.nc", include_str!("../../bench/circle.nc")),
    ("sine.nc", include_str!("../../bench/sine.nc")),
    ("spiral.nc", include_str!("../../bench/spiral.nc")),
];

/// What a soak saw.
#[derive(Debug, Default)]
pub struct Soak {
    pub virtual_s: f64,
    pub jobs: usize,
    pub lines: usize,
    /// Refused lines and alarms.
    pub complaints: Vec<String>,
    pub watchdog_resets: u32,
    pub watchdog_feeds: u64,
    pub hardfaults: u32,
    /// ST7920 instructions that came while it was busy (lost).
    pub lcd_lost: u64,
    pub lcd_bytes: u64,
    pub step_events: usize,
}

impl Soak {
    pub fn passed(&self) -> bool {
        self.complaints.is_empty()
            && self.watchdog_resets == 0
            && self.hardfaults == 0
            && self.lcd_lost == 0
            && self.watchdog_feeds > 0
    }
}

impl std::fmt::Display for Soak {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.1} s of virtual time: {} jobs, {} lines, {} step events, {} complaints; \
             watchdog fed {} times, {} resets; {} HardFaults; LCD {} data bytes, {} lost",
            self.virtual_s,
            self.jobs,
            self.lines,
            self.step_events,
            self.complaints.len(),
            self.watchdog_feeds,
            self.watchdog_resets,
            self.hardfaults,
            self.lcd_bytes,
            self.lcd_lost
        )
    }
}

/// Stream the reference programs over and over for `seconds` of virtual time (the
/// job in progress is finished), asking `?` every 100 ms.
pub fn soak(s: &mut Session, seconds: f64) -> Result<Soak, String> {
    s.boot()?;
    let start = s.now();
    let end = start + (seconds * T_PER_S as f64) as u64;
    let mut out = Soak::default();
    let mut next_status = s.now();
    while s.now() < end {
        let (name, text) = PROGRAMS[out.jobs % PROGRAMS.len()];
        let r = s.stream(text, Flow::CharCount(128), 3600 * T_PER_S, |s| {
            if s.now() >= next_status {
                s.send(b"?");
                next_status = s.now() + 100 * T_PER_MS;
            }
            Ok(())
        })?;
        s.wait_idle(3600 * T_PER_S)
            .map_err(|e| format!("{name}: {e}"))?;
        out.jobs += 1;
        out.lines += r.lines;
        out.complaints.extend(
            r.errors
                .iter()
                .chain(&r.alarms)
                .map(|c| format!("{name}: {c}")),
        );
    }
    let st = s.m.state();
    out.virtual_s = (s.now() - start) as f64 / T_PER_S as f64;
    out.watchdog_resets = st.watchdog_resets;
    out.watchdog_feeds = st.board.iwdg.feeds;
    out.hardfaults = st.hardfaults;
    out.lcd_lost = st.board.lcd.lost;
    out.lcd_bytes = st.board.lcd.writes;
    out.step_events = st.board.steps.len();
    Ok(out)
}
