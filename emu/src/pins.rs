//! What the outside of the board sees and does beyond the USB cable (issue 23, points
//! 1 and 2): how the step trace reads the motion pins (the settings the drivers are
//! wired for), the output pin log as CSV (`--pins`), limit/home switches at positions
//! (`--switch x-:-5mm`) and inputs driven at given times (`--input 1.5s:hold=low`).
//!
//! The step decoder takes its polarities and output mode from the settings stored in
//! the emulated flash (what `$$` says), read with the core's own store, never from the
//! firmware's RAM: a wrong pin level is then a wrong trace, as it would be on a
//! machine whose drivers are wired for the settings the user gave. The firmware saves
//! a setting before it applies it to the pins, so the decoder knows a new polarity
//! before the idle level flips.

use crate::clock::{T_PER_MS, T_PER_S};
use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use inkstep_core::settings::{OutputMode, Settings};
use inkstep_core::settings_store::SettingsStore;

/// The output pins of the README's wiring table: (port, pin, name).
pub const OUTPUTS: [(usize, usize, &str); 13] = [
    (0, 0, "PA0"),
    (0, 1, "PA1"),
    (0, 2, "PA2"),
    (0, 3, "PA3"),
    (0, 4, "PA4"),
    (0, 5, "PA5"),
    (0, 6, "PA6"),
    (0, 7, "PA7"),
    (0, 8, "PA8"),
    (0, 9, "PA9"),
    (0, 10, "PA10"),
    (2, 13, "PC13"),
    (2, 15, "PC15"),
];

/// The watch masks (per port) that log every output of [`OUTPUTS`].
pub const OUTPUT_WATCH: [u32; 3] = [0x7FF, 0, (1 << 13) | (1 << 15)];

/// How the drivers read the motion pins: from the stored settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decode {
    /// `$2`: a set bit makes that axis's step pulse active low.
    pub step_invert: u8,
    /// `$3`: a set bit makes that axis's direction pin high for positive.
    pub dir_invert: u8,
    /// `$200=1`: PA0-PA3 are X's coils A-D, PA4-PA7 Y's.
    pub four_phase: bool,
    /// `$100`-`$102`, for switches given in mm.
    pub steps_per_mm: [f32; 3],
}

impl Default for Decode {
    fn default() -> Decode {
        Decode::from(&Settings::default())
    }
}

impl From<&Settings> for Decode {
    fn from(s: &Settings) -> Decode {
        Decode {
            step_invert: s.step_invert_mask() & 7,
            dir_invert: s.dir_invert_mask() & 7,
            four_phase: s.output_mode() == OutputMode::FourPhase,
            steps_per_mm: [0, 1, 2].map(|a| s.steps_per_mm(a)),
        }
    }
}

impl Decode {
    /// The settings stored in `pages` (the settings region of the flash array), or the
    /// defaults when none are stored yet.
    pub fn from_pages(pages: &[u8]) -> Decode {
        let len = pages.len() as u32;
        let Ok(mut store) = SettingsStore::new(ReadOnly(pages), 0..len) else {
            return Decode::default();
        };
        let mut s = Settings::default();
        let _ = store.load_settings(&mut s);
        Decode::from(&s)
    }
}

/// The flash pages as a store that can only be read (the decoder never writes).
struct ReadOnly<'a>(&'a [u8]);

#[derive(Debug)]
struct ReadOnlyError;

impl NorFlashError for ReadOnlyError {
    fn kind(&self) -> NorFlashErrorKind {
        NorFlashErrorKind::Other
    }
}

impl ErrorType for ReadOnly<'_> {
    type Error = ReadOnlyError;
}

impl ReadNorFlash for ReadOnly<'_> {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), ReadOnlyError> {
        let start = offset as usize;
        let src = self
            .0
            .get(start..start + bytes.len())
            .ok_or(ReadOnlyError)?;
        bytes.copy_from_slice(src);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.0.len()
    }
}

impl NorFlash for ReadOnly<'_> {
    const WRITE_SIZE: usize = 2;
    const ERASE_SIZE: usize = 1024;
    fn erase(&mut self, _: u32, _: u32) -> Result<(), ReadOnlyError> {
        Err(ReadOnlyError)
    }
    fn write(&mut self, _: u32, _: &[u8]) -> Result<(), ReadOnlyError> {
        Err(ReadOnlyError)
    }
}

/// The half-step sequence position of a coil pattern (bit 0 = coil A), if it is one.
pub fn phase_index(coils: u32) -> Option<u8> {
    inkstep_core::stepper::phase4::HALF_STEP
        .iter()
        .position(|&c| u32::from(c) == coils)
        .map(|i| i as u8)
}

/// A limit/home switch at a position: NC, so it opens while the axis is beyond it
/// (below `at_mm` for a `-` switch, above for a `+` one). The X switches share PB1,
/// the Y switches PB3 (wired in series, as each axis has one input).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PosSwitch {
    pub axis: usize,
    /// The switch at the positive end (`x+`).
    pub positive: bool,
    pub at_mm: f32,
}

impl PosSwitch {
    /// `x-:-5.0mm`, `y+:120mm` (the unit may be left out).
    pub fn parse(s: &str) -> Result<PosSwitch, String> {
        let bad = || format!("--switch {s:?}: want AXIS(+|-):POSITION, e.g. x-:-5.0mm");
        let (head, pos) = s.split_once(':').ok_or_else(bad)?;
        let mut c = head.chars();
        let axis = match c.next().map(|c| c.to_ascii_lowercase()) {
            Some('x') => 0,
            Some('y') => 1,
            _ => return Err(bad()),
        };
        let positive = match c.next() {
            Some('+') => true,
            Some('-') => false,
            _ => return Err(bad()),
        };
        if c.next().is_some() {
            return Err(bad());
        }
        let at_mm: f32 = pos
            .trim()
            .trim_end_matches("mm")
            .parse()
            .map_err(|_| bad())?;
        if !at_mm.is_finite() {
            return Err(bad());
        }
        Ok(PosSwitch {
            axis,
            positive,
            at_mm,
        })
    }

    /// Whether the switch is open with the axis at `steps` from power-up.
    pub fn open(&self, steps: i32, steps_per_mm: f32) -> bool {
        let mm = steps as f32 / steps_per_mm;
        if self.positive {
            mm > self.at_mm
        } else {
            mm < self.at_mm
        }
    }
}

/// An input the outside drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// PB0, the NC e-stop: open = pressed.
    Estop,
    /// PB1 / PB3, the NC limit/home switches.
    LimitX,
    LimitY,
    /// PB4, feed hold / SYNC: low = pause.
    Hold,
    /// PB5, cycle start: falling edge = resume.
    Start,
}

/// One change of an input at a time (from the start of the job).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputEvent {
    pub t: u64,
    pub input: Input,
    /// The active state: the switch open, or the input held low.
    pub active: bool,
}

impl InputEvent {
    /// `1.5s:hold=low`, `250ms:estop=open`, `2s:start=pulse` (low for 20 ms, then
    /// released: two events). Names: estop, limit-x, limit-y (open/closed), hold,
    /// start (low/high/pulse).
    pub fn parse(s: &str) -> Result<Vec<InputEvent>, String> {
        let bad = |why: &str| format!("--input {s:?}: {why} (e.g. 1.5s:hold=low)");
        let (time, rest) = s.split_once(':').ok_or_else(|| bad("no time"))?;
        let (name, state) = rest.split_once('=').ok_or_else(|| bad("no state"))?;
        let t = parse_time(time).ok_or_else(|| bad("a time is like 1.5s or 250ms"))?;
        let input = match name.trim() {
            "estop" => Input::Estop,
            "limit-x" => Input::LimitX,
            "limit-y" => Input::LimitY,
            "hold" => Input::Hold,
            "start" => Input::Start,
            _ => return Err(bad("inputs: estop, limit-x, limit-y, hold, start")),
        };
        let switch = matches!(input, Input::Estop | Input::LimitX | Input::LimitY);
        let one = |active| InputEvent { t, input, active };
        Ok(match (state.trim(), switch) {
            ("open", true) | ("low", false) => vec![one(true)],
            ("closed", true) | ("high", false) => vec![one(false)],
            ("pulse", _) => vec![
                one(true),
                InputEvent {
                    t: t + 20 * T_PER_MS,
                    input,
                    active: false,
                },
            ],
            _ => return Err(bad("a switch is open/closed/pulse, a line low/high/pulse")),
        })
    }

    /// A script: one event per line (as `--input`), `#` comments.
    pub fn parse_script(text: &str) -> Result<Vec<InputEvent>, String> {
        let mut all = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if !line.is_empty() {
                all.extend(InputEvent::parse(line).map_err(|e| format!("line {}: {e}", n + 1))?);
            }
        }
        Ok(all)
    }

    /// Apply to what the outside drives.
    pub fn apply(&self, o: &mut crate::board::Outside) {
        let a = self.active;
        match self.input {
            Input::Estop => o.estop_open = a,
            Input::LimitX => o.limit_x_open = a,
            Input::LimitY => o.limit_y_open = a,
            Input::Hold => o.feed_hold_low = a,
            Input::Start => o.cycle_start_low = a,
        }
    }
}

fn parse_time(s: &str) -> Option<u64> {
    let s = s.trim();
    let (num, unit) = if let Some(n) = s.strip_suffix("ms") {
        (n, T_PER_MS)
    } else if let Some(n) = s.strip_suffix("us") {
        (n, T_PER_MS / 1000)
    } else {
        (s.strip_suffix('s').unwrap_or(s), T_PER_S)
    };
    let v: f64 = num.trim().parse().ok()?;
    (v.is_finite() && v >= 0.0).then(|| (v * unit as f64).round() as u64)
}

/// Timed input changes, applied as virtual time passes.
#[derive(Clone, Debug, Default)]
pub struct Schedule {
    events: Vec<InputEvent>,
    next: usize,
    t0: u64,
}

impl Schedule {
    /// Events with times from `t0`.
    pub fn new(mut events: Vec<InputEvent>, t0: u64) -> Schedule {
        events.sort_by_key(|e| e.t);
        Schedule {
            events,
            next: 0,
            t0,
        }
    }

    /// The absolute time of the next change, if any.
    pub fn next_time(&self) -> Option<u64> {
        self.events.get(self.next).map(|e| self.t0 + e.t)
    }

    /// Apply every change due at `now`.
    pub fn apply_due(&mut self, s: &mut crate::session::Session) {
        let mut o = None;
        while let Some(e) = self.events.get(self.next) {
            if self.t0 + e.t > s.now() {
                break;
            }
            let out = o.get_or_insert_with(|| s.m.state().board.outside.clone());
            e.apply(out);
            self.next += 1;
        }
        if let Some(o) = o {
            s.set_outside(o);
        }
    }
}

/// The pin log as CSV: `t_us,pin,value` for every logged change (times from power-up,
/// µs with three decimals), and after each pulse of the servo pin PA8 a row
/// `t_us,PA8_us,width` at its falling edge with the pulse width in µs.
pub fn write_pin_log(
    changes: &[(u64, usize, usize, bool)],
    mut w: impl std::io::Write,
) -> std::io::Result<()> {
    let us = |t: u64| t as f64 / (T_PER_MS as f64 / 1000.0);
    writeln!(w, "t_us,pin,value")?;
    let mut servo_rise = None;
    for &(t, p, n, level) in changes {
        let name = OUTPUTS
            .iter()
            .find(|o| o.0 == p && o.1 == n)
            .map(|o| o.2.to_string())
            .unwrap_or_else(|| format!("P{}{n}", (b'A' + p as u8) as char));
        writeln!(w, "{:.3},{name},{}", us(t), u8::from(level))?;
        if (p, n) == (0, 8) {
            if level {
                servo_rise = Some(t);
            } else if let Some(r) = servo_rise.take() {
                writeln!(w, "{:.3},PA8_us,{:.3}", us(t), us(t - r))?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn switches_and_inputs_parse_and_bad_ones_say_why() {
        assert_eq!(
            PosSwitch::parse("x-:-5.0mm").unwrap(),
            PosSwitch {
                axis: 0,
                positive: false,
                at_mm: -5.0
            }
        );
        assert!(PosSwitch::parse("y+:120").unwrap().positive);
        for bad in ["z-:1", "x:1", "x-", "x-:abc", "x-:inf"] {
            assert!(PosSwitch::parse(bad).is_err(), "{bad}");
        }
        let sw = PosSwitch::parse("x-:-5mm").unwrap();
        assert!(!sw.open(-400, 80.0) && sw.open(-401, 80.0));
        let e = InputEvent::parse("1.5s:hold=low").unwrap();
        assert_eq!(e[0].t, 3 * T_PER_S / 2);
        assert!(e[0].active && e[0].input == Input::Hold);
        assert_eq!(InputEvent::parse("250ms:start=pulse").unwrap().len(), 2);
        assert!(!InputEvent::parse("0:estop=closed").unwrap()[0].active);
        for bad in [
            "1s:hold=open",
            "x:hold=low",
            "1s:door=open",
            "1s:hold",
            "-1s:hold=low",
        ] {
            assert!(InputEvent::parse(bad).is_err(), "{bad}");
        }
        let script = InputEvent::parse_script("# a hold\n1s:hold=low\n1.2s:hold=high\n").unwrap();
        assert_eq!(script.len(), 2);
        assert!(InputEvent::parse_script("1s:hold=sideways")
            .unwrap_err()
            .contains("line 1"));
    }

    #[test]
    fn the_pin_log_gives_each_servo_pulse_its_width() {
        let us = T_PER_MS / 1000;
        let changes = [
            (1000 * us, 0, 8, true),
            (2500 * us, 0, 8, false),
            (3000 * us, 0, 9, true),
            (21000 * us, 0, 8, true),
            (22000 * us, 0, 8, false),
        ];
        let mut out = Vec::new();
        write_pin_log(&changes, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let rows: Vec<&str> = text.lines().collect();
        assert_eq!(rows[0], "t_us,pin,value");
        assert!(rows.contains(&"2500.000,PA8_us,1500.000"), "{text}");
        assert!(rows.contains(&"22000.000,PA8_us,1000.000"), "{text}");
        assert!(rows.contains(&"3000.000,PA9,1"), "{text}");
    }
}
