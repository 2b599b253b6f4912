//! A fake Grbl 1.1 shared by the streaming tests: it models the 128-byte
//! receive buffer (counting every non-real-time byte that arrives and
//! recording any overflow), consumes lines slowly so the buffer really fills,
//! answers `?` with status reports, `!` with a hold and 0x18 with a reset.
//! Lines containing G999 get error:20, lines containing LIMIT raise ALARM:1.
#![allow(dead_code)]

use inkstep_serial::port::Transport;
use std::collections::VecDeque;
use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

pub struct FakeGrbl {
    pub rx: Vec<u8>,
    pub out: VecDeque<u8>,
    pub max_fill: usize,
    pub overflow: bool,
    pub received: Vec<String>,
    pub realtime: Vec<u8>,
    pub state: String,
    pub motion: u32,
    pub tick: u64,
    /// Set `stop` once this many lines were executed.
    pub stop_after: Option<(usize, Arc<AtomicBool>)>,
    /// Receive buffer size (what `Bf:` advertises at rest).
    pub rx_cap: usize,
    /// The link breaks once this many lines were executed.
    pub break_after: Option<usize>,
}

impl FakeGrbl {
    pub fn new() -> Self {
        FakeGrbl {
            rx: Vec::new(),
            out: VecDeque::new(),
            max_fill: 0,
            overflow: false,
            received: Vec::new(),
            realtime: Vec::new(),
            state: "Idle".into(),
            motion: 0,
            tick: 0,
            stop_after: None,
            rx_cap: 128,
            break_after: None,
        }
    }
    fn say(&mut self, s: &str) {
        self.out.extend(s.bytes());
        self.out.extend(b"\r\n");
    }
}

impl Transport for FakeGrbl {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        for &b in bytes {
            match b {
                b'?' => {
                    self.realtime.push(b);
                    let s = format!(
                        "<{}|MPos:0.000,0.000,0.000|Bf:15,{}>",
                        self.state,
                        self.rx_cap - self.rx.len()
                    );
                    self.say(&s);
                }
                b'!' => {
                    self.realtime.push(b);
                    self.state = "Hold:0".into();
                }
                0x18 => {
                    self.realtime.push(b);
                    self.rx.clear();
                    self.motion = 0;
                    self.state = "Idle".into();
                    self.say("Grbl 1.1h ['$' for help]");
                }
                _ => {
                    self.rx.push(b);
                    self.max_fill = self.max_fill.max(self.rx.len());
                    if self.rx.len() > self.rx_cap {
                        self.overflow = true;
                    }
                }
            }
        }
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.tick += 1;
        if self.break_after.is_some_and(|n| self.received.len() >= n) {
            return Err(io::Error::new(io::ErrorKind::BrokenPipe, "link broken"));
        }
        // Execute one line every third poll, unless held or in alarm.
        let running = !self.state.starts_with("Hold") && !self.state.starts_with("Alarm");
        if running && self.tick.is_multiple_of(3) {
            if let Some(i) = self.rx.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.rx.drain(..=i).collect();
                let text = String::from_utf8_lossy(&line[..line.len() - 1]).to_string();
                self.received.push(text.clone());
                if text.contains("G999") {
                    self.say("error:20");
                } else if text.contains("LIMIT") {
                    self.state = "Alarm".into();
                    self.say("ALARM:1");
                } else {
                    self.say("ok");
                    self.motion += 2;
                    self.state = "Run".into();
                }
                if let Some((n, flag)) = &self.stop_after {
                    if self.received.len() >= *n {
                        flag.store(true, Ordering::SeqCst);
                    }
                }
            } else if self.motion > 0 {
                self.motion -= 1;
                if self.motion == 0 && self.state == "Run" {
                    self.state = "Idle".into();
                }
            }
        }
        let n = buf.len().min(self.out.len());
        for (i, b) in self.out.drain(..n).enumerate() {
            buf[i] = b;
        }
        Ok(n)
    }
}
