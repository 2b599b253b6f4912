//! The Grbl 1.1 line protocol over a byte stream (USB CDC-ACM in the firmware, a pty in
//! the simulator).
//!
//! Bytes go in one at a time with [`Protocol::take_byte`]; real-time commands (`?`,
//! `!`, `~`, 0x18, 0x85, overrides, every byte >= 0x80) act at once, even mid-line,
//! and never take buffer space. Other bytes wait in a 128-byte receive buffer, the one
//! senders count characters against; when it is full `take_byte` refuses the byte, so
//! the caller leaves it and the rest in its ring (back-pressure, no byte is ever
//! dropped). [`Protocol::poll_one`] frames a line, runs it through the
//! [`Machine`] and answers `ok` / `error:N`; a line whose motion does not fit the
//! planner queue waits, and so does everything behind it (the machine interprets it
//! once and keeps its commands until they fit). Responses collect in an
//! output buffer drained with [`Protocol::pop_output`]; work that produces output
//! only starts when the buffer has room for it, so responses are never truncated.
//!
//! It is driven from one context, the protocol tick: [`crate::controller::Controller`]
//! boots it from the settings store, hands it the host's bytes ([`Protocol::take_byte`]
//! on each byte the host ring holds, until one is refused), polls it, moves its output
//! to the host ring ([`Protocol::pop_output`]), gives it the input levels
//! ([`Protocol::set_inputs`]) and saves what its `take_*_dirty` report at rest. The
//! e-stop interrupt stops the step engine itself before the tick learns of it through
//! `set_inputs`. docs/architecture.md shows the whole path.

mod commands;
mod report;
mod stream;

use crate::decimal::{put_int, Sink};
use crate::gcode::units::{Nm, NmPos};
use crate::gcode::{ErrorCode, LineCleaner, StartupLine, LINE_MAX, STARTUP_LINES};
use crate::machine::{Inputs, Machine, MotionControl, Taken};
use crate::motion::AXES;
use crate::pending::Work;
use crate::settings::Settings;
use commands::Listing;
use core::mem::MaybeUninit;
use heapless::{Deque, String, Vec};
pub use stream::is_realtime;

/// Receive buffer size advertised to character-counting senders (`Bf:` and `$I`).
pub const RX_BUFFER_SIZE: usize = 128;
/// Output buffer size: the reserve below plus room for a few replies. Replies wait here
/// until the USB task takes them (64 bytes a millisecond); a long listing continues as
/// room frees up.
pub const OUT_CAP: usize = 384;
/// Room kept free before starting anything that writes (the longest single output:
/// a status report or one listing line plus a message).
const OUT_RESERVE: usize = 256;
/// Most `?`s remembered while the output buffer is too full for their reports: each
/// gets its own report as room frees up (500 in one write get 500). Only a flood
/// beyond this many unanswered ones loses the excess (docs/grbl.md).
pub const STATUS_PENDING_MAX: u16 = 1024;
/// Status reports between repeated `WCO:` / `Ov:` fields.
const REFRESH_EVERY: u8 = 10;

/// The welcome line that senders look for.
pub const WELCOME: &str = "Grbl 1.1h ['$' for help]";
const VERSION: &str = env!("CARGO_PKG_VERSION");
/// The longest `(MSG, ...)` comment kept (its first bytes; the rest is dropped): the
/// message's 40 characters and "MSG,". Each byte here is RAM the image is short of.
const COMMENT_CAP: usize = crate::machine::state::MESSAGE_LEN + 4;

/// The protocol handler.
pub struct Protocol {
    machine: Machine,
    rx: Deque<u8, RX_BUFFER_SIZE>,
    line: Vec<u8, LINE_MAX>,
    cleaner: LineCleaner,
    line_too_long: bool,
    /// A complete line waits in `line` for room in the planner.
    line_ready: bool,
    /// The last line ended with CR: a following LF belongs to it.
    after_cr: bool,
    out: Deque<u8, OUT_CAP>,
    /// `?`s waiting for room in the output buffer (each gets its own report).
    status_requested: u16,
    /// A soft reset's welcome waits for room in the output buffer (resets in a row
    /// say it once; nothing is written in part).
    welcome_due: bool,
    listing: Option<Listing>,
    /// The line's first `(...)` comment, as sent (up to [`COMMENT_CAP`] bytes).
    comment: Vec<u8, COMMENT_CAP>,
    /// That comment has ended: later ones on the line are not kept.
    comment_done: bool,
    reports: u8,
    startup: [StartupLine; STARTUP_LINES],
    startup_next: Option<usize>,
    startup_dirty: bool,
    /// The work offset last shown (`WCO:` repeats when it changes).
    wco_shown: NmPos,
    truncated: u32,
    /// Leaving check mode resets; the welcome line follows the `ok`.
    pending_welcome: bool,
    /// The last line's `ok` goes out once the queue has run empty (a G4 after its
    /// dwell); no other line runs before it.
    ok_when_idle: bool,
}

struct OutWriter<'a> {
    out: &'a mut Deque<u8, OUT_CAP>,
    truncated: &'a mut u32,
}

impl Sink for OutWriter<'_> {
    fn put(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.out.push_back(b).is_err() {
                *self.truncated = self.truncated.saturating_add(1);
            }
        }
    }
}

impl Protocol {
    /// Power-up: the welcome line is queued at once.
    pub fn new(settings: Settings) -> Protocol {
        crate::in_place::build(|slot| Protocol::init_in(slot, &settings))
    }

    /// [`Protocol::new`] built in `slot` (the firmware's static cell, through
    /// [`Controller::init_in`](crate::controller::Controller::init_in)): field by field,
    /// so that no whole protocol is built on the stack and copied.
    #[allow(unsafe_code)]
    pub fn init_in<'a>(
        slot: &'a mut MaybeUninit<Protocol>,
        settings: &Settings,
    ) -> &'a mut Protocol {
        let proto = crate::init_fields!(slot => Protocol {
            machine in |cell| Machine::init_in(cell, settings),
            rx = Deque::new(),
            line = Vec::new(),
            cleaner = LineCleaner::new(),
            line_too_long = false,
            line_ready = false,
            after_cr = false,
            out = Deque::new(),
            status_requested = 0,
            welcome_due = false,
            listing = None,
            comment = Vec::new(),
            comment_done = false,
            reports = 0,
            startup = [String::new(), String::new()],
            startup_next = Some(0),
            startup_dirty = false,
            wco_shown = [Nm::MIN; AXES],
            truncated = 0,
            pending_welcome = false,
            ok_when_idle = false,
        });
        proto.welcome();
        proto
    }

    pub fn machine(&self) -> &Machine {
        &self.machine
    }
    /// For the keypad modes and the firmware's loading of stored data.
    pub fn machine_mut(&mut self) -> &mut Machine {
        &mut self.machine
    }
    /// Bytes waiting in the output buffer.
    pub fn output_len(&self) -> usize {
        self.out.len()
    }
    /// Bytes that did not fit the output buffer (0 unless the host never reads).
    pub fn truncated(&self) -> u32 {
        self.truncated
    }
    pub fn startup_line(&self, i: usize) -> Option<&str> {
        self.startup.get(i).map(|s| s.as_str())
    }
    /// Load a stored `$N` line at boot.
    pub fn set_startup_line(&mut self, i: usize, line: StartupLine) {
        if let Some(slot) = self.startup.get_mut(i) {
            *slot = line;
        }
    }
    /// A `$N` line changed and should be saved (cleared by reading).
    pub fn take_startup_dirty(&mut self) -> bool {
        core::mem::take(&mut self.startup_dirty)
    }

    /// Take the oldest byte of the responses (the controller moves them straight
    /// into the host ring).
    pub fn pop_output(&mut self) -> Option<u8> {
        self.out.pop_front()
    }

    fn room(&self) -> usize {
        OUT_CAP - self.out.len()
    }

    fn w(&mut self) -> OutWriter<'_> {
        OutWriter {
            out: &mut self.out,
            truncated: &mut self.truncated,
        }
    }

    /// One response line: `parts` in order, then CR LF.
    fn say(&mut self, parts: &[&[u8]]) {
        let mut w = self.w();
        for p in parts {
            w.put(p);
        }
        w.put(b"\r\n");
    }

    /// A line of `head` and a number (`error:N`, `ALARM:N`).
    fn say_n(&mut self, head: &[u8], n: u8) {
        let mut w = self.w();
        w.put(head);
        put_int(&mut w, i32::from(n));
        w.put(b"\r\n");
    }

    /// Queue a `[MSG:...]` line (e.g. the settings store's load report at boot).
    pub fn notify(&mut self, text: &str) {
        self.say(&[b"[MSG:", text.as_bytes(), b"]"]);
    }

    /// The host opened the port: what was said while nobody listened is dropped, and
    /// the session starts with the welcome line (and how to unlock, in alarm), as a
    /// Grbl board that the opening of its port resets.
    pub fn start_session(&mut self) {
        self.out.clear();
        self.welcome_due = false;
        self.welcome();
    }

    /// Say the welcome again, before the answer to whatever comes next: for a sender
    /// whose first byte comes long after it opened the port, and which may have
    /// thrown away what the board said meanwhile (see
    /// [`crate::controller::WELCOME_REPEAT_MS`]).
    pub fn repeat_welcome(&mut self) {
        self.welcome_due = true;
    }

    /// Drop the waiting output (the port is closed: nobody reads it).
    pub fn discard_output(&mut self) {
        self.out.clear();
    }

    /// Update the input levels (e-stop, limits, feed hold, cycle start).
    pub fn set_inputs<M: MotionControl>(&mut self, inputs: Inputs, m: &mut M, now_ms: u32) {
        self.machine.set_inputs(inputs, m, now_ms);
        if self.room() >= OUT_RESERVE {
            self.flush_events();
        }
    }

    /// The first work the protocol (with its machine, [`Machine::pending`]) still
    /// holds: a complete line, a report, a listing, a startup line or a delayed `ok`
    /// waiting, or a reply not yet read out. Without any, nothing changes until a
    /// byte arrives or an input changes. A poll frames every received byte of a
    /// partial line into the line at once, so bytes wait in the receive buffer only
    /// behind a complete line or until the next poll: an empty buffer is the test
    /// (and, before a poll, the cautious answer).
    pub fn pending<M: MotionControl>(&self, m: &M) -> Option<Work> {
        if let Some(w) = self.machine.pending(m) {
            return Some(w);
        }
        let work = if !self.out.is_empty() {
            Work::Output
        } else if self.line_ready {
            Work::LineReady
        } else if !self.rx.is_empty() {
            Work::Received
        } else if self.status_requested != 0 {
            Work::StatusRequested
        } else if self.welcome_due {
            Work::Welcome
        } else if self.listing.is_some() {
            Work::Listing
        } else if self.startup_next.is_some() {
            Work::StartupLine
        } else if self.pending_welcome {
            Work::PendingWelcome
        } else if self.ok_when_idle {
            Work::OkWhenIdle
        } else {
            return None;
        };
        Some(work)
    }

    /// Test support: hold `w` if it is the protocol's or the machine's kind of
    /// work (`on`), or none of it; false for the other layers' kinds.
    #[cfg(test)]
    pub(crate) fn set_work(&mut self, w: Work, on: bool) -> bool {
        match w {
            Work::Output if on => {
                let _ = self.out.push_back(b'x');
            }
            Work::Output => self.out.clear(),
            Work::LineReady => self.line_ready = on,
            Work::Received if on => {
                let _ = self.rx.push_back(b'x');
            }
            Work::Received => self.rx.clear(),
            Work::StatusRequested => self.status_requested = u16::from(on),
            Work::Welcome => self.welcome_due = on,
            Work::Listing => self.listing = on.then_some(Listing::Settings(0)),
            Work::StartupLine => self.startup_next = on.then_some(0),
            Work::PendingWelcome => self.pending_welcome = on,
            Work::OkWhenIdle => self.ok_when_idle = on,
            _ => return self.machine.set_work(w, on),
        }
        true
    }

    /// Make progress with at most one line (a buffered or a startup line), continue
    /// listings, emit messages:
    /// the shell's protocol task calls it in a loop and lets other work in between
    /// lines (a line with its planning can take a millisecond on the board, and a
    /// `?` must not wait for a whole window of them). True when it ran a line and
    /// another may follow at once.
    pub fn poll_one<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) -> bool {
        self.machine.poll(m, now_ms);
        self.work(m, now_ms)
    }

    /// Replies, listings and messages, then at most one line; true when it ran one.
    fn work<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) -> bool {
        loop {
            if self.room() < OUT_RESERVE {
                return false;
            }
            if core::mem::take(&mut self.welcome_due) {
                self.flush_events();
                self.welcome();
                continue;
            }
            self.flush_events();
            if self.status_requested > 0 {
                self.status_report(m);
                continue;
            }
            if let Some(l) = self.listing {
                self.continue_listing(l);
                continue;
            }
            if let Some(i) = self.startup_next {
                return self.run_startup(i, m, now_ms);
            }
            if self.ok_when_idle {
                if !m.is_idle() {
                    return false;
                }
                self.ok_when_idle = false;
                self.respond(Ok(()));
                continue;
            }
            if !self.line_ready && !self.frame_line() {
                return false;
            }
            return self.run_line(m, now_ms);
        }
    }

    /// Execute the framed line. False if it must wait (planner full).
    fn run_line<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) -> bool {
        if self.line_too_long {
            self.finish_line(Err(ErrorCode::Overflow));
            return true;
        }
        // The line stays where it is while it runs (and if it waits): the machine
        // borrows it beside the fields it changes, so no copy of it sits on the stack
        // under the G-code and reconfiguration paths.
        if self.machine.prompt().is_some() && message_of(&self.comment).is_some() {
            // A new message waits while the machine waits for the user: the prompt
            // keeps the message it was given (a pen change's "pen 2: red" is not
            // replaced by the next layer's before the pen is in).
            return false;
        }
        let r = match self.line.first() {
            None => {
                // Grbl answers blank lines (and lines of only a comment) with ok,
                // but a bare CR LF pair is one line end, not two.
                if !self.machine.check_mode() && !self.machine.is_locked() {
                    self.message();
                }
                Some(Ok(()))
            }
            Some(b'$') => self.system_command(m),
            Some(_) => {
                // Moves carry the line's N number only (0 without one): `Ln:`.
                let r = self.machine.execute(&self.line, 0, m, now_ms);
                if matches!(r, Some(Ok(_))) {
                    self.message();
                }
                if r == Some(Ok(Taken::WhenIdle)) {
                    self.flush_events();
                    self.finish_frame();
                    self.ok_when_idle = true;
                    return true;
                }
                r.map(|r| r.map(|_| ()))
            }
        };
        let Some(r) = r else {
            // Interpreted, planned in the next call (true), or waiting (false).
            return self.machine.take_yielded();
        };
        self.flush_events();
        if self.listing.is_none() || r.is_err() {
            self.listing = if r.is_err() { None } else { self.listing };
            self.finish_line(r);
        } else {
            self.finish_frame();
        }
        true
    }

    /// A `(MSG, text)` comment on the line just run: `[MSG:text]` to the sender, and
    /// the text kept for the LCD. "MSG" in any case, spaces around the comma allowed.
    fn message(&mut self) {
        let comment = core::mem::take(&mut self.comment);
        let Some(text) = message_of(&comment) else {
            return;
        };
        let mut w = self.w();
        w.put(b"[MSG:");
        w.put(text);
        w.put(b"]\r\n");
        self.machine.set_message(text);
    }

    fn finish_line(&mut self, r: Result<(), ErrorCode>) {
        self.finish_frame();
        self.respond(r);
        if core::mem::take(&mut self.pending_welcome) {
            self.welcome();
        }
    }
}

/// The text of a `MSG, text` comment ("MSG" in any case, spaces around the comma).
fn message_of(comment: &[u8]) -> Option<&[u8]> {
    let c = trim_start(comment);
    let rest = c
        .get(3..)
        .filter(|_| c.get(..3).is_some_and(|m| m.eq_ignore_ascii_case(b"MSG")))?;
    Some(trim_start(trim_start(rest).strip_prefix(b",")?))
}

/// `s` without its leading spaces.
fn trim_start(s: &[u8]) -> &[u8] {
    let n = s.iter().take_while(|&&b| b == b' ').count();
    s.get(n..).unwrap_or(&[])
}
