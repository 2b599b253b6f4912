//! Streaming a whole program to a controller in wall-clock time (`cargo host
//! send`): a hello (`?` must be answered, and not in alarm), every line through the
//! one [`Sender`] with character counting against the receive buffer the controller
//! advertises (`Bf:` at rest), status polls, and a clean end: the last `ok` and then
//! an Idle report asked for after it. An `error:N` or a stop request holds the
//! machine, waits for it to come to rest and soft-resets it; an alarm, a restart or
//! a broken link ends the stream naming the oldest unanswered line. Observer
//! callbacks carry progress, status and messages to whatever shows them.

use crate::grbl::{Reply, Status};
use crate::port::Transport;
use crate::sender::{Answer, Event, Flow, Sender};
use inkstep_core::gcode::LineCleaner;
use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Told what happens while streaming (progress bar, status line).
pub trait Observer {
    fn progress(&mut self, acked: usize, total: usize);
    fn status(&mut self, status: &Status);
    fn message(&mut self, text: &str);
    /// True when the user asked to continue (a pen change or an `M0` waits for
    /// cycle start): the stream sends `~`. Asked once per loop; none by default.
    fn cycle_start(&mut self) -> bool {
        false
    }
}

/// A line to send and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// 1-based line in the file.
    pub file_line: usize,
    pub text: String,
}

#[derive(Clone, Debug)]
pub struct Config {
    /// The controller's receive buffer (Grbl: 128); a different size that the
    /// controller advertises in `Bf:` when idle replaces it.
    pub rx_size: usize,
    pub status_interval: Duration,
    /// After the last `ok`, wait until the machine reports Idle.
    pub wait_idle: bool,
    /// How long the controller may take to answer the first `?`.
    pub hello_timeout: Duration,
    /// Longest wait for a feed hold to come to rest before the reset.
    pub hold_timeout: Duration,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            rx_size: 128,
            status_interval: Duration::from_millis(200),
            wait_idle: true,
            hello_timeout: Duration::from_secs(3),
            hold_timeout: Duration::from_secs(5),
        }
    }
}

/// How a stream ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Every line answered `ok` (and the machine is idle if asked to wait).
    Done { lines: usize },
    /// `error:N` for a line: streaming stopped, the machine was held and reset.
    Error {
        file_line: usize,
        text: String,
        code: u32,
    },
    /// `ALARM:N`; the line is the oldest unanswered one, if any.
    Alarm { file_line: Option<usize>, code: u32 },
    /// Stopped by the user: feed hold, then soft reset.
    Interrupted { file_line: Option<usize> },
    /// The controller was already in alarm before the first line.
    Locked { state: String },
    /// The port failed mid-stream.
    Disconnected {
        file_line: Option<usize>,
        error: String,
    },
}

/// A line as Grbl keeps it: comments, spaces and control characters removed and
/// letters upper-cased, by the firmware's own line cleaner.
pub fn clean(raw: &str) -> String {
    let mut c = LineCleaner::new();
    raw.bytes()
        .filter_map(|b| c.push(b))
        .map(char::from)
        .collect()
}

/// Lines worth sending: cleaned as Grbl cleans them (every byte saved is buffer
/// room), empty lines dropped. Fails on a line that cannot fit the receive buffer.
pub fn prepare(program: &str, rx_size: usize) -> Result<Vec<Line>, String> {
    let mut out = Vec::new();
    for (k, raw) in program.lines().enumerate() {
        let text = clean(raw);
        if text.is_empty() {
            continue;
        }
        if text.len() + 1 > rx_size {
            return Err(format!(
                "line {}: {} bytes do not fit the {rx_size}-byte buffer",
                k + 1,
                text.len() + 1
            ));
        }
        out.push(Line {
            file_line: k + 1,
            text,
        });
    }
    Ok(out)
}

/// Receives from the transport and parses what arrived.
fn poll<T: Transport>(t: &mut T, sender: &mut Sender<usize>) -> io::Result<Vec<Event<usize>>> {
    let mut buf = [0u8; 512];
    let n = t.recv(&mut buf)?;
    Ok(sender.received(&buf[..n]))
}

/// Streams `lines`; `stop` set (by Ctrl-C) ends it with hold and reset.
/// A transport failure after the hello (cable pulled, simulator gone) is
/// `Outcome::Disconnected` naming the oldest unanswered line.
pub fn stream<T: Transport>(
    t: &mut T,
    lines: &[Line],
    cfg: &Config,
    stop: &AtomicBool,
    obs: &mut dyn Observer,
) -> io::Result<Outcome> {
    let mut at: Option<Option<usize>> = None;
    match stream_inner(t, lines, cfg, stop, obs, &mut at) {
        Err(e) if at.is_some() => Ok(Outcome::Disconnected {
            file_line: at.flatten(),
            error: e.to_string(),
        }),
        r => r,
    }
}

/// `at` becomes Some once the hello is done, holding the oldest unanswered line.
fn stream_inner<T: Transport>(
    t: &mut T,
    lines: &[Line],
    cfg: &Config,
    stop: &AtomicBool,
    obs: &mut dyn Observer,
    at: &mut Option<Option<usize>>,
) -> io::Result<Outcome> {
    let mut sender: Sender<usize> = Sender::new(Flow::CharCount(cfg.rx_size));
    // Hello: the controller must answer a status request, and not be in alarm.
    t.send(b"?")?;
    let t0 = Instant::now();
    let mut last_poll = Instant::now();
    'hello: loop {
        for e in poll(t, &mut sender)? {
            match e {
                Event::Reply(Reply::Status(s)) => {
                    obs.status(&s);
                    if s.state.starts_with("Alarm") {
                        return Ok(Outcome::Locked { state: s.state });
                    }
                    // At rest the controller's free receive bytes (Bf:) are
                    // its buffer size: use what it advertises if every line fits.
                    let longest = lines.iter().map(|l| l.text.len() + 1).max().unwrap_or(0);
                    if let (true, Some((_, free))) = (s.state == "Idle", s.buffer) {
                        let free = free as usize;
                        if free >= 16 && free >= longest && free != cfg.rx_size {
                            obs.message(&format!("receive buffer {free} bytes (from Bf:)"));
                            sender.set_flow(Flow::CharCount(free));
                        }
                    }
                    break 'hello;
                }
                Event::Reply(Reply::Feedback(m) | Reply::Welcome(m)) => obs.message(&m),
                _ => {}
            }
        }
        if t0.elapsed() > cfg.hello_timeout {
            return Err(io::Error::new(
                io::ErrorKind::TimedOut,
                "no status report from the controller",
            ));
        }
        if last_poll.elapsed() > Duration::from_millis(500) {
            t.send(b"?")?;
            last_poll = Instant::now();
        }
        if stop.load(Ordering::Relaxed) {
            return Ok(Outcome::Interrupted { file_line: None });
        }
    }

    for (i, l) in lines.iter().enumerate() {
        sender.push(i, l.text.as_str());
    }
    let oldest = |s: &Sender<usize>| s.oldest_in_flight().map(|&i| lines[i].file_line);
    let mut acked = 0usize;
    // Status requests sent and not yet answered, and how many of those were
    // asked before the last ok (their answers cannot prove the end).
    let mut polls = 0usize;
    let mut stale: Option<usize> = None;
    obs.progress(0, lines.len());
    loop {
        *at = Some(oldest(&sender));
        if stop.load(Ordering::Relaxed) {
            let at = oldest(&sender);
            hold_and_reset(t, &mut sender, cfg, obs)?;
            return Ok(Outcome::Interrupted { file_line: at });
        }
        let bytes = sender.to_send();
        if !bytes.is_empty() {
            t.send(&bytes)?;
        }
        if obs.cycle_start() {
            t.send(b"~")?;
        }
        if last_poll.elapsed() >= cfg.status_interval {
            t.send(b"?")?;
            polls += 1;
            last_poll = Instant::now();
        }
        for e in poll(t, &mut sender)? {
            match e {
                Event::Answered(_, Answer::Ok) => {
                    acked += 1;
                    obs.progress(acked, lines.len());
                }
                Event::Answered(i, Answer::Error(code)) => {
                    hold_and_reset(t, &mut sender, cfg, obs)?;
                    return Ok(Outcome::Error {
                        file_line: lines[i].file_line,
                        text: lines[i].text.clone(),
                        code,
                    });
                }
                Event::Reply(Reply::Alarm(code)) => {
                    return Ok(Outcome::Alarm {
                        file_line: oldest(&sender),
                        code,
                    })
                }
                Event::Reply(Reply::Status(s)) => {
                    obs.status(&s);
                    polls = polls.saturating_sub(1);
                    match &mut stale {
                        Some(0) if s.state == "Idle" || s.state == "Check" => {
                            return Ok(Outcome::Done { lines: lines.len() })
                        }
                        Some(n) => *n = n.saturating_sub(1),
                        None => {}
                    }
                }
                Event::Reply(Reply::Feedback(m)) => obs.message(&m),
                Event::Reply(Reply::Welcome(m)) => {
                    obs.message(&format!("controller restarted: {m}"));
                    if acked > 0 || sender.in_flight() > 0 {
                        return Ok(Outcome::Alarm {
                            file_line: None,
                            code: 0,
                        });
                    }
                }
                Event::Reply(_) => {}
            }
        }
        if sender.done() {
            if !cfg.wait_idle {
                return Ok(Outcome::Done { lines: lines.len() });
            }
            if stale.is_none() {
                // Only a status asked for after the last ok proves the end.
                stale = Some(polls);
                t.send(b"?")?;
                polls += 1;
                last_poll = Instant::now();
            }
        }
    }
}

/// Feed hold, wait for the machine to come to rest (`Hold:0`, or already
/// Idle), then soft reset so the queue is flushed without losing position.
fn hold_and_reset<T: Transport>(
    t: &mut T,
    sender: &mut Sender<usize>,
    cfg: &Config,
    obs: &mut dyn Observer,
) -> io::Result<()> {
    t.send(b"!")?;
    let t0 = Instant::now();
    let mut last_poll = Instant::now() - cfg.status_interval;
    'wait: while t0.elapsed() < cfg.hold_timeout {
        if last_poll.elapsed() >= Duration::from_millis(100) {
            t.send(b"?")?;
            last_poll = Instant::now();
        }
        for e in poll(t, sender)? {
            if let Event::Reply(Reply::Status(s)) = e {
                obs.status(&s);
                if s.state == "Hold:0" || s.state == "Idle" || s.state.starts_with("Alarm") {
                    break 'wait;
                }
            }
        }
    }
    t.send(&[0x18])?;
    sender.clear();
    // Let the reset's welcome line arrive and be shown.
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(300) {
        for e in poll(t, sender)? {
            if let Event::Reply(Reply::Welcome(m) | Reply::Feedback(m)) = e {
                obs.message(&m);
            }
        }
    }
    Ok(())
}
