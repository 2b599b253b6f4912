//! The Grbl 1.1 line protocol over a byte stream (USB CDC-ACM in the firmware, a pty in
//! the simulator).
//!
//! Bytes go in with [`Protocol::receive`]; real-time commands (`?`, `!`, `~`, 0x18,
//! 0x85, overrides, every byte >= 0x80) act at once, even mid-line, and never take
//! buffer space. Other bytes wait in a 128-byte receive buffer, the one senders count
//! characters against; when it is full `receive` stops consuming and returns how many
//! bytes it took, so the caller leaves the rest in its endpoint (back-pressure, no
//! byte is ever dropped). [`Protocol::poll`] frames lines, runs them through the
//! [`Machine`] and answers `ok` / `error:N`; a line whose motion does not fit the
//! planner queue waits, and so does everything behind it. Responses collect in an
//! output buffer drained with [`Protocol::read_output`]; work that produces output
//! only starts when the buffer has room for it, so responses are never truncated.
//!
//! Driving it (firmware protocol task, simulator loop), all from one context:
//! ```text
//! boot:  (settings, st) = store.load_settings().await
//!        p = Protocol::new(settings); if let Some(t) = st.message() { p.notify(t) }
//!        p.machine_mut().set_coords(store.load_coords().await.0)
//!        for i in 0..STARTUP_LINES { p.set_startup_line(i, &store.load_startup(i).await.0) }
//! loop:  n = p.receive(&usb_rx[..], &mut planner, now_ms)   // drain only n bytes
//!        p.poll(&mut planner, now_ms)            // also every ms or so when idle:
//!                                                  // homing and debounce run on time
//!        usb_tx.write(&buf[..p.read_output(&mut buf)])
//!        p.set_inputs(levels, &mut planner, now_ms)          // on any input change
//!        busy_led.set(p.machine().busy(&planner))
//!        when !busy: save what take_settings_dirty / take_coords_dirty /
//!                    take_startup_dirty report (flash writes stall the CPU)
//! ```
//! The e-stop interrupt stops the step engine itself before the protocol task
//! learns of it through `set_inputs`.

use crate::gcode::{LineCleaner, Status};
use crate::machine::state::Event;
use crate::machine::{Inputs, Machine, MotionControl, RunState};
use crate::motion::AXES;
use crate::settings::round_i32;
use crate::settings::{put_decimal, put_int, write_fixed3, Settings, Sink};
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use heapless::{Deque, String, Vec};

/// Receive buffer size advertised to character-counting senders (`Bf:` and `$I`).
pub const RX_BUFFER_SIZE: usize = 128;
/// Longest line after cleaning (Grbl's limit); longer lines get `error:11`.
pub const LINE_MAX: usize = 80;
/// Output buffer size: the reserve below plus room for a few replies. Replies wait here
/// until the USB task takes them (64 bytes a millisecond); a long listing continues as
/// room frees up.
pub const OUT_CAP: usize = 384;
/// Room kept free before starting anything that writes (the longest single output:
/// a status report or one listing line plus a message).
const OUT_RESERVE: usize = 256;
/// Number of `$N` startup lines.
pub const STARTUP_LINES: usize = 2;
/// Status reports between repeated `WCO:` / `Ov:` fields.
const REFRESH_EVERY: u8 = 10;

/// The welcome line that senders look for.
pub const WELCOME: &str = "Grbl 1.1h ['$' for help]";
const VERSION: &str = env!("CARGO_PKG_VERSION");

/// A startup line as stored.
pub type StartupLine = String<LINE_MAX>;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Listing {
    Settings(usize),
    Coords(usize),
    Startup(usize),
}

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
    status_requested: bool,
    listing: Option<Listing>,
    lines_received: u32,
    reports: u8,
    startup: [StartupLine; STARTUP_LINES],
    startup_next: Option<usize>,
    startup_dirty: bool,
    wco_shown: [f32; AXES],
    truncated: u32,
    /// Leaving check mode resets; the welcome line follows the `ok`.
    pending_welcome: bool,
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

fn axis_triplet(w: &mut dyn Sink, v: &[f32; AXES], scale: f32) {
    for (i, x) in v.iter().enumerate() {
        if i > 0 {
            w.put(b",");
        }
        write_fixed3(w, x / scale);
    }
}

/// A `$` command, told apart before it runs (so that the line's text need not be
/// held while `self` changes).
#[derive(Clone, Copy, PartialEq, Eq)]
enum SysCommand {
    Help,
    List(Listing),
    Modal,
    Info,
    Check,
    Unlock,
    Home,
    Reset(u8),
    Jog,
    Startup,
    Setting,
}

impl SysCommand {
    /// `cmd`: the line after the `$`.
    fn of(cmd: &[u8]) -> SysCommand {
        match cmd {
            [] => SysCommand::Help,
            [b'$'] => SysCommand::List(Listing::Settings(0)),
            [b'#'] => SysCommand::List(Listing::Coords(0)),
            [b'N'] => SysCommand::List(Listing::Startup(0)),
            [b'G'] => SysCommand::Modal,
            [b'I'] => SysCommand::Info,
            [b'C'] => SysCommand::Check,
            [b'X'] => SysCommand::Unlock,
            [b'H'] => SysCommand::Home,
            [b'R', b'S', b'T', b'=', what @ (b'$' | b'#' | b'*')] => SysCommand::Reset(*what),
            [b'J', b'=', ..] => SysCommand::Jog,
            [b'N', ..] => SysCommand::Startup,
            _ => SysCommand::Setting,
        }
    }
}

/// `$n=v`.
fn set_setting<M: MotionControl>(
    machine: &mut Machine,
    cmd: &[u8],
    m: &mut M,
) -> Result<(), Status> {
    let eq = cmd
        .iter()
        .position(|&c| c == b'=')
        .ok_or(Status::InvalidStatement)?;
    let (num, val) = cmd.split_at(eq);
    let val = val.get(1..).unwrap_or(&[]);
    if num.is_empty() || !num.iter().all(u8::is_ascii_digit) || num.len() > 4 {
        return Err(Status::InvalidStatement);
    }
    let n = num
        .iter()
        .fold(0u16, |acc, &d| acc * 10 + u16::from(d - b'0'));
    let (v, used) = crate::gcode::parser::read_number(val)?;
    if used != val.len() {
        return Err(Status::BadNumberFormat);
    }
    machine.set_setting(n, v, m)
}

/// `$Nx=line`: check the line and store it in slot x.
fn store_startup(
    machine: &mut Machine,
    startup: &mut [StartupLine; STARTUP_LINES],
    rest: &[u8],
) -> Result<(), Status> {
    let (idx, line) = match rest {
        [d @ b'0'..=b'9', b'=', line @ ..] => (usize::from(d - b'0'), line),
        _ => return Err(Status::InvalidStatement),
    };
    let slot_exists = idx < STARTUP_LINES;
    if !slot_exists {
        return Err(Status::InvalidStatement);
    }
    machine.validate(line)?;
    // Cleaned lines are ASCII (the cleaner drops bytes >= 0x7F); byte-wise copy
    // keeps UTF-8 validation out of the image.
    if !line.is_ascii() {
        return Err(Status::InvalidStatement);
    }
    if let Some(slot) = startup.get_mut(idx) {
        slot.clear();
        for &b in line.iter().take(LINE_MAX) {
            // Masked: the compiler then knows the char is one UTF-8 byte.
            let _ = slot.push(char::from(b & 0x7F));
        }
    }
    Ok(())
}

impl Protocol {
    /// Power-up: the welcome line is queued at once.
    pub fn new(settings: Settings) -> Protocol {
        crate::in_place::build(|slot| Protocol::init_in(slot, &settings))
    }

    /// [`Protocol::new`] built in `slot` (the firmware's static cell, through
    /// [`Controller::init_in`](crate::controller::Controller::init_in)): field by field,
    /// so that no whole protocol (1.5 KB) is built on the stack and copied.
    #[allow(unsafe_code)]
    pub fn init_in<'a>(
        slot: &'a mut MaybeUninit<Protocol>,
        settings: &Settings,
    ) -> &'a mut Protocol {
        // Lists every field (no `..`): a new field fails to compile here until it is
        // written below too.
        const _: fn(&Protocol) = |Protocol {
                                      machine: _,
                                      rx: _,
                                      line: _,
                                      cleaner: _,
                                      line_too_long: _,
                                      line_ready: _,
                                      after_cr: _,
                                      out: _,
                                      status_requested: _,
                                      listing: _,
                                      lines_received: _,
                                      reports: _,
                                      startup: _,
                                      startup_next: _,
                                      startup_dirty: _,
                                      wco_shown: _,
                                      truncated: _,
                                      pending_welcome: _,
                                  }| {};
        let p = slot.as_mut_ptr();
        // SAFETY: `p` points to `slot`, valid for writes and properly aligned; each field
        // is written once through a raw field pointer (the machine through its own
        // `init_in`, on its field viewed as `MaybeUninit`, which has the same layout)
        // and the list below names every field, so the protocol is initialised when
        // `assume_init_mut` runs.
        let proto = unsafe {
            Machine::init_in(
                &mut *addr_of_mut!((*p).machine).cast::<MaybeUninit<Machine>>(),
                settings,
            );
            addr_of_mut!((*p).rx).write(Deque::new());
            addr_of_mut!((*p).line).write(Vec::new());
            addr_of_mut!((*p).cleaner).write(LineCleaner::new());
            addr_of_mut!((*p).line_too_long).write(false);
            addr_of_mut!((*p).line_ready).write(false);
            addr_of_mut!((*p).after_cr).write(false);
            addr_of_mut!((*p).out).write(Deque::new());
            addr_of_mut!((*p).status_requested).write(false);
            addr_of_mut!((*p).listing).write(None);
            addr_of_mut!((*p).lines_received).write(0);
            addr_of_mut!((*p).reports).write(0);
            addr_of_mut!((*p).startup).write([String::new(), String::new()]);
            addr_of_mut!((*p).startup_next).write(Some(0));
            addr_of_mut!((*p).startup_dirty).write(false);
            addr_of_mut!((*p).wco_shown).write([f32::NAN; AXES]);
            addr_of_mut!((*p).truncated).write(0);
            addr_of_mut!((*p).pending_welcome).write(false);
            slot.assume_init_mut()
        };
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
    /// Free bytes in the receive buffer (what `Bf:` reports).
    pub fn rx_free(&self) -> usize {
        RX_BUFFER_SIZE - self.rx.len()
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
    pub fn set_startup_line(&mut self, i: usize, line: &str) {
        if let Some(slot) = self.startup.get_mut(i) {
            slot.clear();
            let _ = slot.push_str(line.get(..LINE_MAX.min(line.len())).unwrap_or(""));
        }
    }
    /// A `$N` line changed and should be saved (cleared by reading).
    pub fn take_startup_dirty(&mut self) -> bool {
        core::mem::take(&mut self.startup_dirty)
    }

    /// Take up to `buf.len()` bytes of responses.
    pub fn read_output(&mut self, buf: &mut [u8]) -> usize {
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.out.pop_front() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        n
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

    /// A line of `head`, a number and `tail`.
    fn say_n(&mut self, head: &[u8], n: u8, tail: &[u8]) {
        let mut w = self.w();
        w.put(head);
        put_int(&mut w, i32::from(n));
        w.put(tail);
        w.put(b"\r\n");
    }

    fn welcome(&mut self) {
        self.say(&[b"\r\n", WELCOME.as_bytes()]);
    }

    fn respond(&mut self, r: Result<(), Status>) {
        match r {
            Ok(()) => self.say(&[b"ok"]),
            Err(e) => self.say_n(b"error:", e.code(), b""),
        }
    }

    /// Feed received bytes; returns how many were consumed. Bytes not consumed must be
    /// offered again later (the receive buffer was full).
    pub fn receive<M: MotionControl>(&mut self, bytes: &[u8], m: &mut M, now_ms: u32) -> usize {
        let mut used = 0;
        for &b in bytes {
            if !self.realtime(b, m, now_ms) && self.rx.push_back(b).is_err() {
                break;
            }
            used += 1;
        }
        used
    }

    /// Handle `b` if it is a real-time command.
    fn realtime<M: MotionControl>(&mut self, b: u8, m: &mut M, now_ms: u32) -> bool {
        match b {
            b'?' => {
                self.status_requested = true;
                if self.room() >= OUT_RESERVE {
                    self.status_report(m);
                }
            }
            b'!' => self.machine.feed_hold(m),
            b'~' => self.machine.cycle_start(m),
            0x18 => self.soft_reset(m),
            0x84 => self.machine.safety_door(m),
            0x85 => self.machine.jog_cancel(m),
            0x90..=0x97 => self.machine.override_command(b, m),
            // Other extended real-time bytes (door, spindle and coolant overrides)
            // have no meaning on a plotter; never let them into a line.
            0x80..=0xFF => {}
            _ => return false,
        }
        let _ = now_ms;
        true
    }

    fn soft_reset<M: MotionControl>(&mut self, m: &mut M) {
        self.machine.soft_reset(m);
        self.rx.clear();
        self.line.clear();
        self.cleaner.reset();
        self.line_too_long = false;
        self.line_ready = false;
        self.after_cr = false;
        self.listing = None;
        self.lines_received = 0;
        self.startup_next = Some(0);
        self.flush_events();
        self.welcome();
    }

    /// Queue a `[MSG:...]` line (e.g. the settings store's load report at boot).
    pub fn notify(&mut self, text: &str) {
        self.say(&[b"[MSG:", text.as_bytes(), b"]"]);
    }

    /// Update the input levels (e-stop, limits, feed hold, cycle start).
    pub fn set_inputs<M: MotionControl>(&mut self, inputs: Inputs, m: &mut M, now_ms: u32) {
        self.machine.set_inputs(inputs, m, now_ms);
        if self.room() >= OUT_RESERVE {
            self.flush_events();
        }
    }

    fn flush_events(&mut self) {
        while let Some(e) = self.machine.next_event() {
            match e {
                Event::Alarm(a) => self.say_n(b"ALARM:", a.code(), b""),
                Event::Msg(t) => self.say(&[b"[MSG:", t.as_bytes(), b"]"]),
                Event::JobStarted => self.say(&[b"[MSG:Job started]"]),
                Event::JobFinished { ms, moves } => {
                    let mut w = self.w();
                    w.put(b"[MSG:Job finished: ");
                    // Seconds with three decimals: exact, as f32 holds any u32 / 1000
                    // only approximately, so the digits come from the integer.
                    put_decimal(&mut w, u64::from(ms), false, 3);
                    w.put(b" s, ");
                    put_decimal(&mut w, u64::from(moves), false, 0);
                    w.put(b" moves]\r\n");
                }
            }
        }
    }

    /// Make progress: run buffered lines, continue listings, emit messages.
    pub fn poll<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) {
        self.machine.poll(m, now_ms);
        loop {
            if self.room() < OUT_RESERVE {
                return;
            }
            self.flush_events();
            if self.status_requested {
                self.status_report(m);
                continue;
            }
            if let Some(l) = self.listing {
                self.continue_listing(l);
                continue;
            }
            if let Some(i) = self.startup_next {
                if !self.run_startup(i, m, now_ms) {
                    return;
                }
                continue;
            }
            if !self.line_ready && !self.frame_line() {
                return;
            }
            if !self.run_line(m, now_ms) {
                return;
            }
        }
    }

    /// Move bytes from the receive buffer into the line; true when a line is complete.
    fn frame_line(&mut self) -> bool {
        while let Some(b) = self.rx.pop_front() {
            let lf_after_cr = b == b'\n' && self.after_cr;
            self.after_cr = b == b'\r';
            if lf_after_cr {
                continue;
            }
            if b == b'\n' || b == b'\r' {
                self.cleaner.reset();
                self.line_ready = true;
                return true;
            }
            if let Some(c) = self.cleaner.push(b) {
                if self.line.push(c).is_err() {
                    self.line_too_long = true;
                }
            }
        }
        false
    }

    /// Execute the framed line. False if it must wait (planner full).
    fn run_line<M: MotionControl>(&mut self, m: &mut M, now_ms: u32) -> bool {
        if self.line_too_long {
            self.finish_line(Err(Status::Overflow));
            return true;
        }
        // The line stays where it is while it runs (and if it waits): the machine
        // borrows it beside the fields it changes, so no copy of it sits on the stack
        // under the G-code and reconfiguration paths.
        let r = match self.line.first() {
            None => {
                // Grbl answers blank lines (and lines of only a comment) with ok,
                // but a bare CR LF pair is one line end, not two.
                Some(Ok(()))
            }
            Some(b'$') => self.system_command(m),
            Some(_) => {
                let line_no = self.lines_received.wrapping_add(1);
                let r = self.machine.execute(&self.line, line_no, m, now_ms);
                if r.is_some() {
                    self.lines_received = line_no;
                }
                r
            }
        };
        let Some(r) = r else {
            return false;
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

    fn finish_frame(&mut self) {
        self.line.clear();
        self.line_too_long = false;
        self.line_ready = false;
    }

    fn finish_line(&mut self, r: Result<(), Status>) {
        self.finish_frame();
        self.respond(r);
        if core::mem::take(&mut self.pending_welcome) {
            self.welcome();
        }
    }

    /// The `$` command in `line`. `None` if the command must wait for planner room.
    fn system_command<M: MotionControl>(&mut self, m: &mut M) -> Option<Result<(), Status>> {
        let at_rest = matches!(
            self.machine.state(m),
            RunState::Idle | RunState::Alarm | RunState::Check
        );
        let kind = SysCommand::of(self.line.get(1..).unwrap_or(&[]));
        // Everything but help, $G, $C (checks itself) and jogging needs the machine at
        // rest; refuse before doing anything.
        let anytime = matches!(
            kind,
            SysCommand::Help | SysCommand::Modal | SysCommand::Check | SysCommand::Jog
        );
        if !anytime && !at_rest {
            return Some(Err(Status::IdleError));
        }
        Some(match kind {
            SysCommand::Help => {
                self.say(&[b"[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $C $X $H $RST=$ $RST=# $RST=* ~ ! ? ctrl-x]"]);
                Ok(())
            }
            SysCommand::List(l) => {
                self.listing = Some(l);
                Ok(())
            }
            SysCommand::Modal => {
                let mut w = OutWriter {
                    out: &mut self.out,
                    truncated: &mut self.truncated,
                };
                w.put(b"[");
                self.machine.interp().write_modal(&mut w);
                w.put(b"]\r\n");
                Ok(())
            }
            SysCommand::Info => {
                self.say(&[
                    b"[VER:1.1h.inkstep-",
                    VERSION.as_bytes(),
                    b":inkstep pen plotter]",
                ]);
                let cap = m.capacity();
                let mut w = self.w();
                w.put(b"[OPT:NL,");
                put_int(&mut w, cap as i32);
                w.put(b",");
                put_int(&mut w, RX_BUFFER_SIZE as i32);
                w.put(b"]\r\n");
                Ok(())
            }
            SysCommand::Check => {
                let was = self.machine.check_mode();
                let r = self.machine.toggle_check(m);
                if was && r.is_ok() {
                    self.flush_events();
                    self.startup_next = Some(0);
                    self.welcome_after_ok();
                }
                r
            }
            SysCommand::Unlock => self.machine.unlock(),
            SysCommand::Home => self.machine.start_homing(m),
            // $RST=$ settings, $RST=# coordinate data, $RST=* both.
            SysCommand::Reset(what) => {
                if what != b'#' {
                    self.machine.replace_settings(Settings::default(), m);
                }
                if what != b'$' {
                    self.machine.clear_coords();
                }
                Ok(())
            }
            // These read the line's text: borrowed in place, beside the fields they
            // change.
            SysCommand::Jog => {
                if m.free() == 0 {
                    return None;
                }
                self.machine.jog(self.line.get(3..).unwrap_or(&[]), m)
            }
            SysCommand::Startup => {
                let rest = self.line.get(2..).unwrap_or(&[]);
                let r = store_startup(&mut self.machine, &mut self.startup, rest);
                if r.is_ok() {
                    self.startup_dirty = true;
                }
                r
            }
            SysCommand::Setting => {
                set_setting(&mut self.machine, self.line.get(1..).unwrap_or(&[]), m)
            }
        })
    }

    fn welcome_after_ok(&mut self) {
        self.pending_welcome = true;
    }

    /// Run stored startup line `i` (after reset, when not locked). False to wait.
    /// The line is borrowed where it is stored (the machine and the output are other
    /// fields), not moved out: no copy of it sits on the stack under the G-code path.
    fn run_startup<M: MotionControl>(&mut self, i: usize, m: &mut M, now_ms: u32) -> bool {
        if self.machine.is_locked() {
            self.startup_next = None;
            return true;
        }
        let Some(text) = self.startup.get(i) else {
            self.startup_next = None;
            return true;
        };
        self.startup_next = Some(i + 1);
        if text.is_empty() {
            return true;
        }
        let Some(r) = self.machine.execute(text.as_bytes(), 0, m, now_ms) else {
            self.startup_next = Some(i);
            return false;
        };
        self.flush_events();
        let text = self.startup.get(i).map_or(&[][..], |t| t.as_bytes());
        let mut w = OutWriter {
            out: &mut self.out,
            truncated: &mut self.truncated,
        };
        w.put(b">");
        w.put(text);
        match r {
            Ok(()) => w.put(b":ok"),
            Err(e) => {
                w.put(b":error:");
                put_int(&mut w, i32::from(e.code()));
            }
        }
        w.put(b"\r\n");
        true
    }

    fn continue_listing(&mut self, l: Listing) {
        let next = self.listing_line(l);
        self.listing = next;
        if next.is_none() {
            self.say(&[b"ok"]);
        }
    }

    /// Write one line of a listing; the next step, `None` past the end.
    fn listing_line(&mut self, l: Listing) -> Option<Listing> {
        let machine = &self.machine;
        let mut w = OutWriter {
            out: &mut self.out,
            truncated: &mut self.truncated,
        };
        let next = match l {
            Listing::Settings(i) => {
                machine.settings().write_entry(i, &mut w)?;
                Listing::Settings(i + 1)
            }
            Listing::Coords(i) => {
                let interp = machine.interp();
                let c = interp.coords();
                let v = match i {
                    0..=5 => c.wcs.get(i),
                    6 => Some(&c.g28),
                    7 => Some(&c.g30),
                    8 => Some(interp.g92()),
                    9 => {
                        w.put(b"[TLO:0.000]");
                        None
                    }
                    10 => {
                        w.put(b"[PRB:0.000,0.000,0.000:0]");
                        None
                    }
                    _ => return None,
                };
                if let Some(v) = v {
                    // [G54:..] .. [G59:..], [G28:..], [G30:..], [G92:..].
                    let mut head = *b"[G54:";
                    if let (Some(code), Some(d)) = (
                        b"545556575859283092".get(2 * i..2 * i + 2),
                        head.get_mut(2..4),
                    ) {
                        d.copy_from_slice(code);
                    }
                    w.put(&head);
                    let scale = if machine.settings().report_inches() {
                        25.4
                    } else {
                        1.0
                    };
                    axis_triplet(&mut w, v, scale);
                    w.put(b"]");
                }
                Listing::Coords(i + 1)
            }
            Listing::Startup(i) => {
                let text = self.startup.get(i)?;
                w.put(b"$N");
                put_int(&mut w, i as i32);
                w.put(b"=");
                w.put(text.as_bytes());
                Listing::Startup(i + 1)
            }
        };
        w.put(b"\r\n");
        Some(next)
    }

    /// `<State|MPos:...|FS:...|Bf:...|...>`.
    fn status_report<M: MotionControl>(&mut self, m: &M) {
        self.status_requested = false;
        self.reports = self.reports.wrapping_add(1);
        let reports = self.reports;
        // Each value is fetched where it is written: fewer live values to spill. The
        // writer borrows only the output fields, so the machine stays reachable.
        let machine = &mut self.machine;
        let mut w = OutWriter {
            out: &mut self.out,
            truncated: &mut self.truncated,
        };
        w.put(match machine.state(m) {
            RunState::Idle => b"<Idle",
            RunState::Run => b"<Run",
            RunState::Hold { complete: true } => b"<Hold:0",
            RunState::Hold { complete: false } => b"<Hold:1",
            RunState::Jog => b"<Jog",
            RunState::Door { at_rest: true } => b"<Door:0",
            RunState::Door { at_rest: false } => b"<Door:2",
            RunState::Alarm => b"<Alarm",
            RunState::Home => b"<Home",
            RunState::Check => b"<Check",
        });
        let settings = machine.settings();
        let scale = if settings.report_inches() { 25.4 } else { 1.0 };
        let mask = settings.status_mask();
        let mut pos = machine.machine_position(m);
        let wco = machine.interp().work_offset();
        if mask & 1 != 0 {
            w.put(b"|MPos:");
        } else {
            for (p, o) in pos.iter_mut().zip(wco.iter()) {
                *p -= o;
            }
            w.put(b"|WPos:");
        }
        axis_triplet(&mut w, &pos, scale);
        if mask & 2 != 0 {
            w.put(b"|Bf:");
            put_int(&mut w, m.free() as i32);
            w.put(b",");
            put_int(&mut w, (RX_BUFFER_SIZE - self.rx.len()) as i32);
        }
        w.put(b"|FS:");
        put_int(&mut w, round_i32(m.speed() / scale));
        w.put(b",");
        // The pen is the spindle: report S while it is down.
        let interp = machine.interp();
        put_int(
            &mut w,
            if interp.modal().pen_down {
                round_i32(interp.spindle())
            } else {
                0
            },
        );
        let inputs = machine.inputs();
        let pins = [
            inputs.limits[0],
            inputs.limits[1],
            inputs.limits[2],
            inputs.feed_hold,
            inputs.cycle_start,
            inputs.estop,
        ];
        if pins.contains(&true) {
            w.put(b"|Pn:");
            for (on, c) in pins.iter().zip(b"XYZHSE".chunks(1)) {
                if *on {
                    w.put(c);
                }
            }
        }
        if reports % REFRESH_EVERY == 1 || wco != self.wco_shown {
            w.put(b"|WCO:");
            axis_triplet(&mut w, &wco, scale);
            self.wco_shown = wco;
        }
        if machine.take_overrides_changed() || reports % REFRESH_EVERY == 6 {
            let (fo, ro) = machine.overrides();
            w.put(b"|Ov:");
            put_int(&mut w, i32::from(fo));
            w.put(b",");
            put_int(&mut w, i32::from(ro));
            w.put(b",100");
        }
        w.put(b">\r\n");
    }
}
