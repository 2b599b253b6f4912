//! A session with the emulated board as a user has it: the firmware image (built with
//! `cargo build --release` unless one is given), the board booted, the USB port
//! enumerated by the host, and bytes exchanged with it the way a sender does. The
//! commands (`main.rs`) and the tests drive the board through this.

use crate::board::Outside;
use crate::clock::{T_PER_MS, T_PER_S};
use crate::elf::Image;
use crate::machine::{Machine, Stop};
use crate::periph::flash::Flash;
use inkstep_serial::grbl::Reply;
use inkstep_serial::sender::{Answer, Event, Flow, Sender};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The release product image, built first (what `cargo run --release` flashes).
pub fn product_elf() -> Result<PathBuf, String> {
    let root = repo_root();
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["build", "--release", "--bin", "inkstep"])
        .current_dir(&root)
        .status()
        .map_err(|e| format!("cargo build --release: {e}"))?;
    if !status.success() {
        return Err("cargo build --release failed".into());
    }
    Ok(root.join("target/thumbv7m-none-eabi/release/inkstep"))
}

/// The workspace root (emu/ is one level down).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

pub struct Session<'a> {
    pub m: Machine<'a>,
    /// Everything the board sent, as text.
    pub received: String,
    /// The image's symbols (name to address).
    symbols: std::collections::HashMap<String, u32>,
    /// Input changes at given times (`--input`), applied as time passes.
    pub inputs: crate::pins::Schedule,
    /// Real-time bytes to send at times after the first step (`--realtime`, as
    /// `cargo sim run --realtime`), in time order, and how many went out.
    pub realtime: Vec<inkstep_sim::run::Realtime>,
    pub realtime_sent: usize,
}

impl<'a> Session<'a> {
    /// A board with `elf` flashed, its flash array kept in `flash_file` if given.
    pub fn new(elf: &Path, flash_file: Option<&Path>) -> Result<Session<'a>, String> {
        let image = Image::read(elf)?;
        let flash = Flash::new(flash_file).map_err(|e| format!("flash file: {e}"))?;
        let m = Machine::new(&image, flash)?;
        Ok(Session {
            m,
            received: String::new(),
            symbols: image.symbols,
            inputs: crate::pins::Schedule::default(),
            realtime: Vec::new(),
            realtime_sent: 0,
        })
    }

    pub fn now(&self) -> u64 {
        self.m.now()
    }

    /// The address of the image's symbol `name`.
    pub fn symbol(&self, name: &str) -> Option<u32> {
        self.symbols.get(name).copied()
    }

    /// The word at `addr` as the CPU sees it (RAM or flash).
    pub fn read_u32(&self, addr: u32) -> Option<u32> {
        self.m.read_u32(addr)
    }

    /// Run `t` more time units; a stop is an error (with the log's tail).
    pub fn run_for(&mut self, t: u64) -> Result<(), String> {
        let until = self.m.now() + t;
        self.run_to(until)
    }

    pub fn run_to(&mut self, until: u64) -> Result<(), String> {
        loop {
            // Stop at each scheduled input change and real-time byte, so that it
            // comes at its time (before the first step, every 125 µs while real-time
            // bytes wait for it).
            let mut to = match self.inputs.next_time() {
                Some(t) if t < until => t,
                _ => until,
            };
            if let Some(r) = self.realtime.get(self.realtime_sent) {
                let d = r.at_us * (T_PER_MS / 1000);
                let t = match self.m.state().board.steps.get(r.after_step) {
                    Some(from) => from.t + d,
                    // Its step has not come yet: look again no later than the byte's
                    // offset after it, so that it goes out on time.
                    None => self.now() + crate::usb_host::SLOT_T.min(d.max(1)),
                };
                to = to.min(t.max(self.now()));
            }
            if let Some(stop) = self.m.run_until(to) {
                return Err(self.stopped(stop));
            }
            if self.inputs.next_time().is_some() {
                let mut inputs = std::mem::take(&mut self.inputs);
                inputs.apply_due(self);
                self.inputs = inputs;
            }
            while let Some(r) = self.realtime.get(self.realtime_sent) {
                let Some(from) = self.m.state().board.steps.get(r.after_step) else {
                    break;
                };
                if from.t + r.at_us * (T_PER_MS / 1000) > self.now() {
                    break;
                }
                let bytes = r.bytes.clone();
                self.send(&bytes);
                self.realtime_sent += 1;
            }
            if to >= until {
                break;
            }
        }
        self.collect();
        Ok(())
    }

    /// Why a real-time byte is still unsent, if it waits for a step event that has
    /// not come (a resume timed from a step the hold stopped short of leaves the
    /// hold waiting for ever), for a time-out's message.
    fn realtime_waiting(&self) -> String {
        let made = self.m.state().board.steps.len();
        match self.realtime.get(self.realtime_sent) {
            Some(r) if r.after_step >= made => format!(
                " (a real-time byte was never sent: it is timed from step event #{}, and the job made {made})",
                r.after_step
            ),
            _ => String::new(),
        }
    }

    /// The message for a stop, with the last lines of the defmt log.
    pub fn stopped(&self, stop: Stop) -> String {
        let mut msg = format!(
            "the board stopped at {:.3} ms: {stop}",
            self.m.now() as f64 / T_PER_MS as f64
        );
        if let Some(log) = &self.m.state().log {
            for l in log.lines.iter().rev().take(5).rev() {
                msg.push_str("\n  log: ");
                msg.push_str(l);
            }
        }
        msg
    }

    fn collect(&mut self) {
        let rx = std::mem::take(&mut self.m.board().host.rx);
        self.received.push_str(&String::from_utf8_lossy(&rx));
    }

    /// Bytes from the host's side of the cable.
    pub fn send(&mut self, bytes: &[u8]) {
        self.m.board().host.tx.extend(bytes.iter().copied());
    }

    /// Take what arrived since the last call.
    pub fn take_received(&mut self) -> String {
        self.collect();
        std::mem::take(&mut self.received)
    }

    /// Boot until the host has configured the port (and DTR is up).
    pub fn boot(&mut self) -> Result<(), String> {
        let limit = self.now() + 2 * T_PER_S;
        while !self.m.state().board.host.configured {
            if self.now() >= limit {
                return Err("the USB port did not enumerate within 2 s".into());
            }
            self.run_for(T_PER_MS)?;
        }
        // The class driver's SET_CONTROL_LINE_STATE follows the configuration.
        self.run_for(5 * T_PER_MS)
    }

    /// Send `line` and wait for its answer (`ok` or `error:N`); returns what came.
    pub fn command(&mut self, line: &str, timeout: u64) -> Result<String, String> {
        self.send(format!("{line}\n").as_bytes());
        let limit = self.now() + timeout;
        let mut got = String::new();
        loop {
            self.run_for(T_PER_MS)?;
            got.push_str(&self.take_received());
            if got
                .lines()
                .any(|l| l.trim() == "ok" || l.trim().starts_with("error:"))
            {
                return Ok(got);
            }
            if self.now() >= limit {
                return Err(format!("no answer to {line:?} (got {got:?})"));
            }
        }
    }

    /// Ask `?` and return the status report (waits up to 50 ms for it); what else
    /// arrived meanwhile stays in `received`.
    pub fn status(&mut self) -> Result<inkstep_serial::grbl::Status, String> {
        self.send(b"?");
        let mut got = String::new();
        for _ in 0..50 {
            self.run_for(T_PER_MS)?;
            got.push_str(&self.take_received());
            if let Some(i) = got.find('<') {
                if let Some(j) = got[i..].find('>') {
                    let report = got[i..i + j + 1].to_string();
                    self.received = format!("{}{}", &got[..i], &got[i + j + 1..]);
                    if let Reply::Status(st) = inkstep_serial::grbl::parse_reply(&report) {
                        return Ok(st);
                    }
                    return Err(format!("unreadable status report {report:?}"));
                }
            }
        }
        self.received = got;
        Err("no status report within 50 ms".into())
    }

    /// Ask `?` until the status report says `Idle` (or the limit).
    pub fn wait_idle(&mut self, limit: u64) -> Result<String, String> {
        self.wait_idle_each(limit, |_| Ok(()))
    }

    /// [`Session::wait_idle`], calling `each` after every status query (20 ms).
    pub fn wait_idle_each(
        &mut self,
        limit: u64,
        mut each: impl FnMut(&mut Session) -> Result<(), String>,
    ) -> Result<String, String> {
        let end = self.now() + limit;
        loop {
            self.send(b"?");
            self.run_for(20 * T_PER_MS)?;
            each(self)?;
            let got = self.take_received();
            if let Some(report) = got.lines().find(|l| l.starts_with("<Idle")) {
                return Ok(report.to_string());
            }
            if let Some(report) = got.lines().find(|l| l.starts_with("<Alarm")) {
                return Err(format!("alarm: {report}"));
            }
            if self.now() >= end {
                return Err("the machine did not come to rest".into());
            }
        }
    }

    pub fn set_outside(&mut self, o: Outside) {
        self.m.board().set_outside(o);
    }

    /// Stream G-code `text` through the USB port with the project's sender (`flow`:
    /// send-response or character counting), calling `each` after every step of the
    /// sender (one host-controller slot, 125 µs, the time a program on the PC takes to
    /// react), until every line is answered (the machine may still be moving: see
    /// `wait_idle`). `error:` answers and alarms are collected, not fatal.
    pub fn stream(
        &mut self,
        text: &str,
        flow: Flow,
        limit: u64,
        mut each: impl FnMut(&mut Session) -> Result<(), String>,
    ) -> Result<Streamed, String> {
        let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
        let mut sender = Sender::new(flow);
        for (i, l) in lines.iter().enumerate() {
            sender.push(i + 1, *l);
        }
        let mut out = Streamed {
            lines: lines.len(),
            ..Streamed::default()
        };
        let note = |events: Vec<Event<usize>>, out: &mut Streamed| {
            for e in events {
                match e {
                    Event::Answered(n, Answer::Error(code)) => out
                        .errors
                        .push(format!("line {n}: {} -> error:{code}", lines[n - 1])),
                    Event::Reply(Reply::Alarm(code)) => out.alarms.push(format!("ALARM:{code}")),
                    _ => {}
                }
            }
        };
        let start = self.now();
        let got = self.take_received();
        note(sender.received(got.as_bytes()), &mut out);
        while !sender.done() {
            let bytes = sender.to_send();
            self.send(&bytes);
            self.run_for(crate::usb_host::SLOT_T)?;
            let got = self.take_received();
            note(sender.received(got.as_bytes()), &mut out);
            each(self)?;
            if self.now() - start > limit {
                return Err(format!(
                    "the job was not answered in time{}",
                    self.realtime_waiting()
                ));
            }
        }
        Ok(out)
    }
}

/// What a streamed job got back.
#[derive(Debug, Default)]
pub struct Streamed {
    pub lines: usize,
    /// `line N: TEXT -> error:C` for every refused line.
    pub errors: Vec<String>,
    pub alarms: Vec<String>,
}
