//! Streaming a program with Grbl's character-counting flow control.
//!
//! Grbl has a 128-byte receive buffer. The sender keeps the byte count of
//! every line sent but not yet answered (`ok` or `error:N`) and sends the
//! next line only if it still fits, so the buffer never overflows and the
//! planner never starves. Real-time bytes (`?`, `!`, 0x18) bypass the buffer
//! and are not counted. This module is the protocol logic only, over a
//! `Transport` trait, so the tests drive it against an in-process fake Grbl
//! that checks the 128-byte rule; send.rs puts a serial port and a terminal
//! UI around it.

use super::grbl::{parse_reply, Reply, Status};
use std::collections::VecDeque;
use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A byte pipe to the controller.
pub trait Transport {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Receives what has arrived, waiting only briefly; 0 when nothing did.
    fn recv(&mut self, buf: &mut [u8]) -> io::Result<usize>;
}

/// Told what happens while streaming (progress bar, status line).
pub trait Observer {
    fn progress(&mut self, acked: usize, total: usize);
    fn status(&mut self, status: &Status);
    fn message(&mut self, text: &str);
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

/// Lines worth sending: comments and spaces removed (Grbl ignores spaces,
/// and every byte saved is buffer room), empty lines dropped. Fails on a
/// line that cannot fit the receive buffer.
pub fn prepare(program: &str, rx_size: usize) -> Result<Vec<Line>, String> {
    let mut out = Vec::new();
    for (k, raw) in program.lines().enumerate() {
        let text: String = crate::gcode_in::strip_comment(raw)
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect();
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

/// Receives whole lines from the transport.
struct Rx {
    acc: Vec<u8>,
}

impl Rx {
    fn poll<T: Transport>(&mut self, t: &mut T) -> io::Result<Vec<Reply>> {
        let mut buf = [0u8; 512];
        let n = t.recv(&mut buf)?;
        self.acc.extend_from_slice(&buf[..n]);
        let mut out = Vec::new();
        while let Some(i) = self.acc.iter().position(|&b| b == b'\n') {
            let line: Vec<u8> = self.acc.drain(..=i).collect();
            let s = String::from_utf8_lossy(&line);
            if !s.trim().is_empty() {
                out.push(parse_reply(&s));
            }
        }
        Ok(out)
    }
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
    let mut rx = Rx { acc: Vec::new() };
    let mut rx_size = cfg.rx_size;
    // Hello: the controller must answer a status request, and not be in alarm.
    t.send(b"?")?;
    let t0 = Instant::now();
    let mut last_poll = Instant::now();
    'hello: loop {
        for r in rx.poll(t)? {
            match r {
                Reply::Status(s) => {
                    obs.status(&s);
                    if s.state.starts_with("Alarm") {
                        return Ok(Outcome::Locked { state: s.state });
                    }
                    // At rest the controller's free receive bytes (Bf:) are
                    // its buffer size: use what it advertises if every line fits.
                    let longest = lines.iter().map(|l| l.text.len() + 1).max().unwrap_or(0);
                    if let (true, Some((_, free))) = (s.state == "Idle", s.buffer) {
                        let free = free as usize;
                        if free >= 16 && free >= longest && free != rx_size {
                            obs.message(&format!("receive buffer {free} bytes (from Bf:)"));
                            rx_size = free;
                        }
                    }
                    break 'hello;
                }
                Reply::Feedback(m) | Reply::Welcome(m) => obs.message(&m),
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

    let mut in_flight: VecDeque<(usize, usize)> = VecDeque::new(); // (index, bytes)
    let mut used = 0usize;
    let (mut next, mut acked) = (0usize, 0usize);
    // Status requests sent and not yet answered, and how many of those were
    // asked before the last ok (their answers cannot prove the end).
    let mut polls = 0usize;
    let mut stale: Option<usize> = None;
    obs.progress(0, lines.len());
    loop {
        *at = Some(in_flight.front().map(|f| lines[f.0].file_line));
        if stop.load(Ordering::Relaxed) {
            let at = in_flight.front().map(|f| lines[f.0].file_line);
            hold_and_reset(t, &mut rx, cfg, obs)?;
            return Ok(Outcome::Interrupted { file_line: at });
        }
        // A line costs its bytes plus the newline.
        while next < lines.len() && used + (lines[next].text.len() + 1) <= rx_size {
            let l = &lines[next];
            let mut bytes = Vec::with_capacity(l.text.len() + 1);
            bytes.extend_from_slice(l.text.as_bytes());
            bytes.push(b'\n');
            t.send(&bytes)?;
            used += bytes.len();
            in_flight.push_back((next, bytes.len()));
            next += 1;
        }
        if last_poll.elapsed() >= cfg.status_interval {
            t.send(b"?")?;
            polls += 1;
            last_poll = Instant::now();
        }
        for r in rx.poll(t)? {
            match r {
                Reply::Ok => {
                    if let Some((_, n)) = in_flight.pop_front() {
                        used -= n;
                        acked += 1;
                        obs.progress(acked, lines.len());
                    }
                }
                Reply::Error(code) => {
                    let (i, _) = in_flight.pop_front().unwrap_or((next.saturating_sub(1), 0));
                    hold_and_reset(t, &mut rx, cfg, obs)?;
                    return Ok(Outcome::Error {
                        file_line: lines[i].file_line,
                        text: lines[i].text.clone(),
                        code,
                    });
                }
                Reply::Alarm(code) => {
                    return Ok(Outcome::Alarm {
                        file_line: in_flight.front().map(|f| lines[f.0].file_line),
                        code,
                    })
                }
                Reply::Status(s) => {
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
                Reply::Feedback(m) => obs.message(&m),
                Reply::Welcome(m) => {
                    obs.message(&format!("controller restarted: {m}"));
                    if next > 0 {
                        return Ok(Outcome::Alarm {
                            file_line: None,
                            code: 0,
                        });
                    }
                }
                Reply::Other(_) => {}
            }
        }
        if next == lines.len() && in_flight.is_empty() {
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
    rx: &mut Rx,
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
        for r in rx.poll(t)? {
            if let Reply::Status(s) = r {
                obs.status(&s);
                if s.state == "Hold:0" || s.state == "Idle" || s.state.starts_with("Alarm") {
                    break 'wait;
                }
            }
        }
    }
    t.send(&[0x18])?;
    // Let the reset's welcome line arrive and be shown.
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(300) {
        for r in rx.poll(t)? {
            if let Reply::Welcome(m) | Reply::Feedback(m) = r {
                obs.message(&m);
            }
        }
    }
    Ok(())
}
