//! 4x4 matrix keypad: debounce, press / repeat / release events, and the keymap.
//!
//! The firmware drives one column low per scan tick (every ~5 ms), reads the four row
//! lines and hands the row bits to [`Keypad::feed`]; this module owns everything after
//! that. It is shaped after the lab report's two scan functions and the three problems
//! they hit (report section 3.11):
//! - `keyscan()` waited for release (one step per press) and `keyscan2()` returned the
//!   key on every loop pass (a held digit filled every field). Here the scan never waits
//!   and never re-reports a held key: each debounced key produces exactly one
//!   [`KeyKind::Press`] and one [`KeyKind::Release`]. So one press never enters a digit
//!   twice (problem 1), a jog key is "move on Press, stop on Release" (problem 2:
//!   holding moves continuously, letting go stops), and speed +/- act on Press only
//!   (problem 3: exactly one change per press, no waiting loop).
//! - [`KeyKind::Repeat`] is produced only for keys where auto-repeat is useful
//!   ([`Key::repeats`]: backspace and the menu up/down keys), never for digits.
//!
//! # Keymap (rows top to bottom, columns left to right, as printed on common keypads)
//!
//! ```text
//!  +-------+-------+-------+-----------+
//!  | 1  ↖  | 2  ↑  | 3  ↗  | A  ▲ / F+ |
//!  | 4  ←  | 5 pen | 6  →  | B  ▼ / F- |
//!  | 7  ↙  | 8  ↓  | 9  ↘  | C  ⌫ / esc|
//!  | *  ±  | 0     | #  .  | D  enter  |
//!  +-------+-------+-------+-----------+
//! ```
//! - Digits 0-9 enter numbers; `*` toggles the sign, `#` is the decimal point.
//! - `A`/`B`: up/down in menus and between form fields; speed + / speed - while jogging.
//! - `C`: backspace while editing a number; on an untouched field, or anywhere else,
//!   cancel / back to the menu; while drawing, abort (feed hold, then clear the queue).
//! - `D`: enter / confirm; while drawing, pause (feed hold) and resume.
//! - Jog: the eight keys around `5` move in the direction of their position on the pad
//!   (`2` = +Y, `8` = -Y, `4` = -X, `6` = +X, corners diagonal) while held; `5` toggles
//!   the pen.
//!
//! Ghosting: a diode-less matrix cannot resolve three keys pressed at the corners of a
//! rectangle; the phantom fourth key then reads as pressed. Nothing here needs chords
//! (diagonals are single keys), so this is accepted, not corrected.

/// Number of row lines (inputs) and column lines (driven outputs).
pub const ROWS: usize = 4;
pub const COLS: usize = 4;

/// A key, named by its function (see the module keymap).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Key {
    /// Digit 0..=9 (also the jog directions and pen toggle in jog mode).
    Digit(u8),
    /// `*`: sign (+/-).
    Sign,
    /// `#`: decimal point.
    Dot,
    /// `A`: up / previous / speed +.
    Up,
    /// `B`: down / next / speed -.
    Down,
    /// `C`: backspace / cancel / abort.
    Back,
    /// `D`: enter / confirm / pause-resume.
    Enter,
}

/// The keymap: `KEYMAP[row][col]`.
pub const KEYMAP: [[Key; COLS]; ROWS] = [
    [Key::Digit(1), Key::Digit(2), Key::Digit(3), Key::Up],
    [Key::Digit(4), Key::Digit(5), Key::Digit(6), Key::Down],
    [Key::Digit(7), Key::Digit(8), Key::Digit(9), Key::Back],
    [Key::Sign, Key::Digit(0), Key::Dot, Key::Enter],
];

/// The legend printed on the keys (row-major, same order as [`KEYMAP`]).
pub const LEGEND: [[&str; COLS]; ROWS] = [
    ["1", "2", "3", "A"],
    ["4", "5", "6", "B"],
    ["7", "8", "9", "C"],
    ["*", "0", "#", "D"],
];

impl Key {
    /// The legend printed on this key.
    pub fn label(self) -> &'static str {
        for (r, row) in KEYMAP.iter().enumerate() {
            for (c, k) in row.iter().enumerate() {
                if *k == self {
                    return LEGEND.get(r).and_then(|l| l.get(c)).copied().unwrap_or("?");
                }
            }
        }
        "?"
    }

    /// Whether holding this key auto-repeats. Digits never do (one press, one digit).
    pub fn repeats(self) -> bool {
        matches!(self, Key::Back | Key::Up | Key::Down)
    }

    /// The jog direction of this key as (dx, dy) signs, if it is one of the eight
    /// keys around `5`. +Y is "up" on the pad (away from the user).
    pub fn jog_dir(self) -> Option<[i8; 2]> {
        // Digits 1-9 as laid out on the pad: columns -X, 0, +X; rows +Y, 0, -Y.
        let Key::Digit(d @ 1..=9) = self else {
            return None;
        };
        let (col, row) = ((d - 1) % 3, (d - 1) / 3);
        let dir = [col as i8 - 1, 1 - row as i8];
        (dir != [0, 0]).then_some(dir)
    }
}

/// What happened to a key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum KeyKind {
    /// Debounced press: once per physical press.
    Press,
    /// Auto-repeat while held (only keys with [`Key::repeats`]).
    Repeat,
    /// Debounced release.
    Release,
}

/// One keypad event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KeyEvent {
    pub key: Key,
    pub kind: KeyKind,
}

/// Timing of debounce and auto-repeat, in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KeypadConfig {
    /// A key's raw level must stay unchanged this long before its state changes.
    /// With one column per 5 ms tick each key is sampled every 20 ms, so 15 ms means
    /// "two equal consecutive samples".
    pub debounce_ms: u32,
    /// Hold time before the first repeat.
    pub repeat_delay_ms: u32,
    /// Interval between repeats.
    pub repeat_interval_ms: u32,
}

impl Default for KeypadConfig {
    fn default() -> Self {
        KeypadConfig {
            debounce_ms: 15,
            repeat_delay_ms: 500,
            repeat_interval_ms: 120,
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct KeyState {
    raw: bool,
    stable: bool,
    changed_at: u32,
    next_repeat: u32,
}

/// Events from one column scan: at most one per key of that column, in row order.
/// Plain data (a copy, iterated by value without a drop or bounds check).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanEvents {
    /// The first `len` are the events.
    events: [KeyEvent; ROWS],
    len: u8,
}

impl ScanEvents {
    const fn new() -> Self {
        // Filler for the unused slots.
        let none = KeyEvent {
            key: Key::Back,
            kind: KeyKind::Release,
        };
        ScanEvents {
            events: [none; ROWS],
            len: 0,
        }
    }

    fn push(&mut self, ev: KeyEvent) {
        if let Some(slot) = self.events.get_mut(usize::from(self.len)) {
            *slot = ev;
            self.len += 1;
        }
    }

    pub fn as_slice(&self) -> &[KeyEvent] {
        self.events.get(..usize::from(self.len)).unwrap_or(&[])
    }

    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl IntoIterator for ScanEvents {
    type Item = KeyEvent;
    type IntoIter = ScanIter;
    fn into_iter(self) -> ScanIter {
        ScanIter {
            events: self,
            at: 0,
        }
    }
}

/// The events of a [`ScanEvents`], by value.
#[derive(Clone, Debug)]
pub struct ScanIter {
    events: ScanEvents,
    at: u8,
}

impl Iterator for ScanIter {
    type Item = KeyEvent;
    fn next(&mut self) -> Option<KeyEvent> {
        let ev = self.events.as_slice().get(usize::from(self.at)).copied()?;
        self.at += 1;
        Some(ev)
    }
}

/// The keypad scanner state.
#[derive(Debug)]
pub struct Keypad {
    cfg: KeypadConfig,
    keys: [[KeyState; COLS]; ROWS],
    col: usize,
}

impl Keypad {
    pub fn new(cfg: KeypadConfig) -> Self {
        Keypad {
            cfg,
            keys: [[KeyState::default(); COLS]; ROWS],
            col: 0,
        }
    }

    /// The column the firmware must drive (low) before reading the rows for the next
    /// [`Keypad::feed`].
    pub fn column(&self) -> usize {
        self.col
    }

    /// Feed the rows read while [`Keypad::column`] was driven (bit r set = row r
    /// pressed, i.e. already inverted from the active-low pins), then advance to the
    /// next column.
    pub fn feed(&mut self, rows: u8, now_ms: u32) -> ScanEvents {
        let col = self.col;
        self.col = (self.col + 1) % COLS;
        self.scan_column(col, rows, now_ms)
    }

    /// Process the row bits of an explicit column (for firmware that scans all four
    /// columns in one tick). Columns out of range produce no events.
    pub fn scan_column(&mut self, col: usize, rows: u8, now_ms: u32) -> ScanEvents {
        let mut out = ScanEvents::new();
        if col >= COLS {
            return out;
        }
        let cfg = self.cfg;
        for (row, keys) in self.keys.iter_mut().enumerate() {
            let Some(k) = keys.get_mut(col) else { continue };
            let Some(key) = KEYMAP.get(row).and_then(|r| r.get(col)).copied() else {
                continue;
            };
            let raw = rows & (1 << row) != 0;
            if raw != k.raw {
                k.raw = raw;
                k.changed_at = now_ms;
            }
            let event = if k.raw != k.stable && now_ms.wrapping_sub(k.changed_at) >= cfg.debounce_ms
            {
                k.stable = k.raw;
                if k.stable {
                    k.next_repeat = now_ms.wrapping_add(cfg.repeat_delay_ms);
                    Some(KeyKind::Press)
                } else {
                    Some(KeyKind::Release)
                }
            } else if k.stable && key.repeats() && reached(now_ms, k.next_repeat) {
                k.next_repeat = k.next_repeat.wrapping_add(cfg.repeat_interval_ms);
                // A long stall between scans must not release a burst of repeats.
                if reached(now_ms, k.next_repeat) {
                    k.next_repeat = now_ms.wrapping_add(cfg.repeat_interval_ms);
                }
                Some(KeyKind::Repeat)
            } else {
                None
            };
            if let Some(kind) = event {
                // Room for one event per row.
                out.push(KeyEvent { key, kind });
            }
        }
        out
    }

    /// Whether `key` is currently held (debounced).
    pub fn is_held(&self, key: Key) -> bool {
        KEYMAP
            .iter()
            .zip(self.keys.iter())
            .any(|(map_row, state_row)| {
                map_row
                    .iter()
                    .zip(state_row.iter())
                    .any(|(k, s)| *k == key && s.stable)
            })
    }
}

/// `now` is at or past `deadline`, on a wrapping millisecond clock.
fn reached(now: u32, deadline: u32) -> bool {
    (now.wrapping_sub(deadline) as i32) >= 0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Row bit and column of a key in the keymap.
    fn pos(key: Key) -> (u8, usize) {
        for (r, row) in KEYMAP.iter().enumerate() {
            for (c, k) in row.iter().enumerate() {
                if *k == key {
                    return (1 << r, c);
                }
            }
        }
        panic!("key not in map");
    }

    /// Run full scan cycles (4 ticks of 5 ms) from `t` to `t_end` with `held` pressed,
    /// letting `bounce` flip the raw level on the given ticks; collect events.
    fn run(
        kp: &mut Keypad,
        t: &mut u32,
        t_end: u32,
        held: Option<Key>,
        bounce: &dyn Fn(u32) -> bool,
    ) -> std::vec::Vec<KeyEvent> {
        let mut ev = std::vec::Vec::new();
        while *t < t_end {
            let col = kp.column();
            let mut rows = 0;
            if let Some(k) = held {
                let (bit, c) = pos(k);
                if c == col && !bounce(*t) {
                    rows = bit;
                }
            }
            ev.extend(kp.feed(rows, *t));
            *t += 5;
        }
        ev
    }

    fn press(key: Key) -> KeyEvent {
        KeyEvent {
            key,
            kind: KeyKind::Press,
        }
    }
    fn release(key: Key) -> KeyEvent {
        KeyEvent {
            key,
            kind: KeyKind::Release,
        }
    }

    #[test]
    fn bouncy_digit_press_is_one_press_and_one_release() {
        let mut kp = Keypad::new(KeypadConfig::default());
        let mut t = 0;
        let k = Key::Digit(3);
        // Contact bounces during the first 12 ms, then is held for 2 s (far past the
        // repeat delay): digits must still be reported once.
        let ev = run(&mut kp, &mut t, 2000, Some(k), &|t| t < 12 && t % 10 == 5);
        assert_eq!(ev, [press(k)]);
        assert!(kp.is_held(k));
        let ev = run(&mut kp, &mut t, 2100, None, &|_| false);
        assert_eq!(ev, [release(k)]);
        assert!(!kp.is_held(k));
    }

    #[test]
    fn a_single_sample_glitch_is_ignored() {
        let mut kp = Keypad::new(KeypadConfig::default());
        // One sample of key 1 (column 0) pressed, then released on its next sample.
        let mut events = std::vec::Vec::new();
        events.extend(kp.scan_column(0, 0b0001, 0));
        events.extend(kp.scan_column(0, 0b0000, 20));
        events.extend(kp.scan_column(0, 0b0000, 40));
        assert!(events.is_empty(), "{events:?}");
    }

    #[test]
    fn backspace_auto_repeats_after_the_delay() {
        let cfg = KeypadConfig::default();
        let mut kp = Keypad::new(cfg);
        let mut t = 0;
        let ev = run(&mut kp, &mut t, 1000, Some(Key::Back), &|_| false);
        let presses = ev.iter().filter(|e| e.kind == KeyKind::Press).count();
        let repeats = ev.iter().filter(|e| e.kind == KeyKind::Repeat).count();
        assert_eq!(presses, 1);
        // Press at 20 ms (two samples of column 2), repeats from 520 ms every 120 ms,
        // checked every 20 ms: 520, 640, 760, 880 (and 1000 is not reached).
        assert_eq!(repeats, 4, "{ev:?}");
    }

    #[test]
    fn jog_key_held_then_released_gives_press_then_release_only() {
        let mut kp = Keypad::new(KeypadConfig::default());
        let mut t = 0;
        let k = Key::Digit(6);
        let held = run(&mut kp, &mut t, 3000, Some(k), &|_| false);
        let released = run(&mut kp, &mut t, 3100, None, &|_| false);
        assert_eq!(held, [press(k)]);
        assert_eq!(released, [release(k)]);
    }

    #[test]
    fn two_keys_in_one_column_are_both_reported() {
        let mut kp = Keypad::new(KeypadConfig::default());
        // Column 3 holds A (row 0) and D (row 3).
        assert!(kp.scan_column(3, 0b1001, 0).is_empty());
        let ev = kp.scan_column(3, 0b1001, 20);
        assert_eq!(ev.as_slice(), [press(Key::Up), press(Key::Enter)]);
        assert!(kp.scan_column(7, 0xff, 40).is_empty());
    }

    #[test]
    fn repeat_deadline_survives_clock_wrap() {
        let mut kp = Keypad::new(KeypadConfig::default());
        let t0 = u32::MAX - 100;
        assert!(kp.scan_column(3, 0b0001, t0).is_empty());
        assert_eq!(
            kp.scan_column(3, 0b0001, t0.wrapping_add(20)).as_slice(),
            [press(Key::Up)]
        );
        // Before the delay: nothing; after it (past the wrap): one repeat.
        assert!(kp.scan_column(3, 0b0001, t0.wrapping_add(300)).is_empty());
        let ev = kp.scan_column(3, 0b0001, t0.wrapping_add(540));
        assert_eq!(
            ev.as_slice(),
            [KeyEvent {
                key: Key::Up,
                kind: KeyKind::Repeat
            }]
        );
    }

    #[test]
    fn every_jog_key_maps_to_a_distinct_direction() {
        let mut dirs = std::vec::Vec::new();
        for d in 0..10 {
            if let Some(dir) = Key::Digit(d).jog_dir() {
                assert!(!dirs.contains(&dir));
                assert_ne!(dir, [0, 0]);
                dirs.push(dir);
            }
        }
        assert_eq!(dirs.len(), 8);
        // Each key moves the way it sits around 5 on the pad (the module's keymap).
        let around_five = [
            (1, [-1, 1]),
            (2, [0, 1]),
            (3, [1, 1]),
            (4, [-1, 0]),
            (6, [1, 0]),
            (7, [-1, -1]),
            (8, [0, -1]),
            (9, [1, -1]),
        ];
        for (d, dir) in around_five {
            assert_eq!(Key::Digit(d).jog_dir(), Some(dir), "key {d}");
        }
        for key in [
            Key::Digit(0),
            Key::Digit(5),
            Key::Digit(10),
            Key::Up,
            Key::Sign,
        ] {
            assert_eq!(key.jog_dir(), None, "{key:?}");
        }
    }
}
