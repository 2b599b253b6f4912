//! The machine link of the web view: one thread owns the serial port and the one
//! Grbl sender (inkstep-serial), polls the status, runs jobs and single commands,
//! and tells every browser what happened.
//!
//! Browsers' requests arrive on a channel; everything the link learns goes out
//! as JSON messages on a broadcast channel, and into a snapshot that a browser
//! joining later is sent first (status, settings, the job and the path drawn so
//! far). The path is built from status reports: each new position is a point,
//! marked pen-down from the Z height ($205/$206) or, with a servo pen ($201=1),
//! from the spindle value inkstep reports while the pen is down.
//!
//! A job's lines all go into the sender, which keeps the controller's receive
//! buffer full without overflowing it; an `error:N`, a stop or a reset ends the
//! job with a feed hold, a wait for rest, and a soft reset, as `cargo host send`
//! does. The link reopens the port when it goes away.

use super::job::{Job, Tracker};
use crate::geom::Pt;
use inkstep_serial::grbl::{alarm_text, error_text, Reply, Status};
use inkstep_serial::port::{Port, Transport};
use inkstep_serial::sender::{Answer, Event, Flow, Sender};
use serde_json::{json, Value};
use std::collections::{BTreeMap, VecDeque};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::broadcast;

/// What a browser asks of the machine.
pub enum Request {
    /// A real-time byte: `!` hold, `~` resume, 0x18 reset, 0x85 jog cancel,
    /// 0x90.. overrides.
    Realtime(u8),
    /// A line (`$X`, `$H`, `$J=...`, `$110=2500`, `$$`); answered with its id.
    Line {
        id: u64,
        text: String,
    },
    /// Makes this the job shown and run next.
    Load(Box<Job>),
    Run,
    Stop,
}

/// Status polls per second.
const STATUS_HZ: u64 = 20;
/// Log lines kept for browsers that join later.
const LOG_KEEP: usize = 100;
/// Path points kept (a long job at 20 reports a second: about 14 hours).
const PATH_KEEP: usize = 1_000_000;

/// What a browser joining now is sent first.
#[derive(Default)]
pub struct Snapshot {
    pub link: Option<Value>,
    pub status: Option<Value>,
    pub settings: Option<Value>,
    pub job: Option<Value>,
    pub path: Vec<[f64; 3]>,
    pub log: VecDeque<Value>,
    /// The pen's work position, for planning a text or SVG from there.
    pub pen: Pt,
    /// Rapid rate (mm/min) for time estimates.
    pub rapid: f64,
}

/// Shared between the link thread and the web handlers.
pub struct Hub {
    pub out: broadcast::Sender<Arc<str>>,
    pub snapshot: Mutex<Snapshot>,
}

impl Hub {
    pub fn new() -> Arc<Hub> {
        Arc::new(Hub {
            out: broadcast::channel(4096).0,
            snapshot: Mutex::new(Snapshot {
                rapid: 3000.0,
                ..Snapshot::default()
            }),
        })
    }

    fn snapshot(&self) -> std::sync::MutexGuard<'_, Snapshot> {
        // A panic elsewhere while holding the lock leaves data that is still
        // whole (plain values); keep serving it.
        self.snapshot.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Sends a message to every browser (none listening is fine).
    pub fn publish(&self, msg: &Value) {
        let _ = self.out.send(msg.to_string().into());
    }

    /// The messages that bring a new browser up to date.
    pub fn catch_up(&self) -> Vec<Value> {
        let s = self.snapshot();
        let mut v: Vec<Value> = [&s.link, &s.settings, &s.job, &s.status]
            .into_iter()
            .flatten()
            .cloned()
            .collect();
        v.push(json!({"t": "path", "pts": s.path}));
        v.extend(s.log.iter().cloned());
        v
    }

    pub fn pen_and_rapid(&self) -> (Pt, f64) {
        let s = self.snapshot();
        (s.pen, s.rapid)
    }

    fn log(&self, text: &str) {
        let m = json!({"t": "log", "text": text});
        let mut s = self.snapshot();
        s.log.push_back(m.clone());
        if s.log.len() > LOG_KEEP {
            s.log.pop_front();
        }
        drop(s);
        self.publish(&m);
    }
}

/// Who a line sent belongs to.
#[derive(Clone, Copy, Debug)]
enum Origin {
    Job(usize),
    /// A browser's command; `setting` when it is `$N=V` (the table is read again).
    Command {
        id: u64,
        setting: bool,
    },
    /// The link's own `$$` after connecting or a settings change.
    Listing,
}

struct Running {
    started: Instant,
    acked: usize,
    tracker: Tracker,
    done_s: f64,
    /// Idle reports seen since the last line was answered.
    idle_reports: u32,
}

struct Link {
    hub: Arc<Hub>,
    sender: Sender<Origin>,
    job: Option<Job>,
    running: Option<Running>,
    /// Feed hold sent, waiting for rest before the soft reset.
    stopping: Option<Instant>,
    settings: BTreeMap<u16, String>,
    listing: BTreeMap<u16, String>,
    wco: [f64; 3],
    overrides: [u32; 3],
    last: Option<[f64; 3]>,
}

/// Runs the link to `port` until `requests` closes.
pub fn run(port: String, hub: Arc<Hub>, requests: Receiver<Request>) {
    let mut link = Link {
        hub,
        sender: Sender::new(Flow::CharCount(128)),
        job: None,
        running: None,
        stopping: None,
        settings: BTreeMap::new(),
        listing: BTreeMap::new(),
        wco: [0.0; 3],
        overrides: [100; 3],
        last: None,
    };
    loop {
        let mut p = match Port::open(&port, 115_200) {
            Ok(p) => p,
            Err(e) => {
                link.set_link(&port, false, &e.to_string());
                if !link.idle_wait(&requests, Duration::from_secs(1)) {
                    return;
                }
                continue;
            }
        };
        link.set_link(&port, true, "");
        match link.serve(&mut p, &requests) {
            Ok(()) => return,
            Err(e) => {
                link.abort_job(&format!("connection lost: {e}"));
                link.sender.clear();
                link.set_link(&port, false, &e.to_string());
                if !link.idle_wait(&requests, Duration::from_secs(1)) {
                    return;
                }
            }
        }
    }
}

impl Link {
    fn set_link(&mut self, port: &str, up: bool, error: &str) {
        let m = json!({"t": "link", "port": port, "up": up, "error": error});
        self.hub.snapshot().link = Some(m.clone());
        self.hub.publish(&m);
    }

    /// While the port is away: answers requests, waits. False once the web
    /// side is gone.
    fn idle_wait(&mut self, requests: &Receiver<Request>, d: Duration) -> bool {
        let end = Instant::now() + d;
        while Instant::now() < end {
            match requests.try_recv() {
                Ok(Request::Line { id, .. }) => self.answer(id, Err("no connection".into())),
                Ok(Request::Load(job)) => self.load(*job),
                Ok(_) => {}
                Err(TryRecvError::Empty) => std::thread::sleep(Duration::from_millis(20)),
                Err(TryRecvError::Disconnected) => return false,
            }
        }
        true
    }

    fn serve<T: Transport>(
        &mut self,
        p: &mut T,
        requests: &Receiver<Request>,
    ) -> std::io::Result<()> {
        self.sender.push(Origin::Listing, "$$");
        p.send(b"?")?;
        let poll_every = Duration::from_millis(1000 / STATUS_HZ);
        let mut last_poll = Instant::now();
        let mut buf = [0u8; 1024];
        loop {
            loop {
                match requests.try_recv() {
                    Ok(r) => self.request(p, r)?,
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => return Ok(()),
                }
            }
            let bytes = self.sender.to_send();
            if !bytes.is_empty() {
                p.send(&bytes)?;
            }
            if last_poll.elapsed() >= poll_every {
                p.send(b"?")?;
                last_poll = Instant::now();
            }
            if self
                .stopping
                .is_some_and(|t| t.elapsed() > Duration::from_secs(5))
            {
                self.reset(p)?;
            }
            let n = p.recv(&mut buf)?;
            for e in self.sender.received(&buf[..n]) {
                self.event(p, e)?;
            }
        }
    }

    fn request<T: Transport>(&mut self, p: &mut T, r: Request) -> std::io::Result<()> {
        match r {
            Request::Realtime(0x18) => {
                if self.running.is_some() {
                    self.abort_job("stopped by a soft reset");
                }
                self.reset(p)?;
            }
            Request::Realtime(b) => p.send(&[b])?,
            Request::Line { id, text } => {
                if self.running.is_some() {
                    self.answer(id, Err("a job is running".into()));
                } else if text == "$$" {
                    // Read into the table, which every browser is sent.
                    self.sender.push(Origin::Listing, text);
                    self.answer(id, Ok(()));
                } else {
                    let setting = text.starts_with('$')
                        && text[1..].starts_with(|c: char| c.is_ascii_digit());
                    self.sender.push(Origin::Command { id, setting }, text);
                }
            }
            Request::Load(job) => {
                if self.running.is_some() {
                    self.hub
                        .log("a job is running: stop it before loading another");
                } else {
                    self.load(*job);
                }
            }
            Request::Run => self.start_job(),
            Request::Stop => {
                if self.running.is_some() && self.stopping.is_none() {
                    self.sender.drop_queued();
                    p.send(b"!")?;
                    self.stopping = Some(Instant::now());
                    self.abort_job("stopped: feed hold, then soft reset");
                }
            }
        }
        Ok(())
    }

    /// Soft reset: the controller drops its buffer, so do the lines in it.
    fn reset<T: Transport>(&mut self, p: &mut T) -> std::io::Result<()> {
        p.send(&[0x18])?;
        self.sender.clear();
        self.stopping = None;
        Ok(())
    }

    fn load(&mut self, job: Job) {
        let left_out: Vec<serde_json::Value> = job
            .left_out
            .iter()
            .map(|s| {
                let rings: Vec<Vec<[f64; 2]>> = s
                    .outline
                    .iter()
                    .map(|r| r.iter().map(|p| [p.x, p.y]).collect())
                    .collect();
                json!({"kind": s.kind.label(), "name": s.name, "outline": rings})
            })
            .collect();
        let m = json!({
            "t": "job",
            "name": job.name,
            "lines": job.lines.len(),
            "est_s": job.total_s(),
            "preview": job.preview(),
            "left_out": left_out,
            "page": job.page.map(|(w, h)| [w, h]),
        });
        self.hub.snapshot().job = Some(m.clone());
        self.hub.publish(&m);
        self.hub.log(&format!(
            "loaded {}: {} lines, about {:.0} s",
            job.name,
            job.lines.len(),
            job.total_s()
        ));
        for s in &job.left_out {
            self.hub
                .log(&format!("not drawn ({}): {}", s.kind.label(), s.name));
        }
        self.job = Some(job);
    }

    fn start_job(&mut self) {
        if self.running.is_some() {
            return;
        }
        let Some(job) = &self.job else {
            self.hub.log("nothing loaded to run");
            return;
        };
        for (i, l) in job.lines.iter().enumerate() {
            self.sender.push(Origin::Job(i), l.text.as_str());
        }
        self.running = Some(Running {
            started: Instant::now(),
            acked: 0,
            tracker: Tracker::new(),
            done_s: 0.0,
            idle_reports: 0,
        });
        self.hub.snapshot().path.clear();
        self.last = None;
        self.hub.publish(&json!({"t": "clear"}));
        self.hub.log(&format!("running {}", job.name));
    }

    fn abort_job(&mut self, why: &str) {
        if self.running.take().is_some() {
            self.sender.drop_queued();
            self.hub.log(why);
            self.hub
                .publish(&json!({"t": "done", "ok": false, "why": why}));
        }
    }

    fn answer(&self, id: u64, r: Result<(), String>) {
        let m = match r {
            Ok(()) => json!({"t": "answer", "id": id, "ok": true}),
            Err(e) => json!({"t": "answer", "id": id, "ok": false, "error": e}),
        };
        self.hub.publish(&m);
    }

    fn event<T: Transport>(&mut self, p: &mut T, e: Event<Origin>) -> std::io::Result<()> {
        match e {
            Event::Answered(Origin::Job(i), a) => {
                if let Some(r) = &mut self.running {
                    r.acked += 1;
                    r.idle_reports = 0;
                }
                if let Answer::Error(n) = a {
                    let line = self.job.as_ref().map_or(0, |j| j.lines[i].file_line);
                    let why = format!("line {line}: error:{n} ({}); stopped", error_text(n));
                    self.sender.drop_queued();
                    p.send(b"!")?;
                    self.stopping = Some(Instant::now());
                    self.abort_job(&why);
                }
            }
            Event::Answered(Origin::Command { id, setting }, a) => {
                let r = match a {
                    Answer::Ok => Ok(()),
                    Answer::Error(n) => Err(format!("error:{n} ({})", error_text(n))),
                };
                self.answer(id, r);
                if setting && a == Answer::Ok {
                    self.sender.push(Origin::Listing, "$$");
                }
            }
            Event::Answered(Origin::Listing, _) => self.publish_settings(),
            Event::Reply(Reply::Setting(n, v)) => {
                self.listing.insert(n, v);
            }
            Event::Reply(Reply::Status(s)) => self.status(p, &s)?,
            Event::Reply(Reply::Alarm(n)) => {
                self.abort_job(&format!("ALARM:{n} ({})", alarm_text(n)));
                self.hub.log(&format!("ALARM:{n} ({})", alarm_text(n)));
            }
            Event::Reply(Reply::Welcome(w)) => {
                // The controller restarted: whatever was in its buffer is gone
                // (its settings may have changed too: read them again).
                self.sender.clear();
                self.stopping = None;
                self.abort_job("the controller restarted");
                self.hub.log(&w);
                self.sender.push(Origin::Listing, "$$");
            }
            Event::Reply(Reply::Feedback(f)) => self.hub.log(&format!("[{f}]")),
            Event::Reply(Reply::Ok | Reply::Error(_) | Reply::Other(_)) => {}
        }
        Ok(())
    }

    fn publish_settings(&mut self) {
        self.settings = std::mem::take(&mut self.listing);
        let list: Vec<Value> = self
            .settings
            .iter()
            .map(|(n, v)| {
                let name = inkstep_core::settings::TABLE
                    .iter()
                    .find(|d| d.number == *n)
                    .map_or("", |d| d.name);
                json!([n, v, name])
            })
            .collect();
        let rapid = [110u16, 111]
            .iter()
            .filter_map(|n| self.settings.get(n)?.parse::<f64>().ok())
            .fold(f64::INFINITY, f64::min);
        let m = json!({"t": "settings", "list": list});
        let mut s = self.hub.snapshot();
        if rapid.is_finite() {
            s.rapid = rapid;
        }
        s.settings = Some(m.clone());
        drop(s);
        self.hub.publish(&m);
    }

    fn setting(&self, n: u16) -> Option<f64> {
        self.settings.get(&n)?.parse().ok()
    }

    /// Whether the pen is down in this report.
    fn pen_down(&self, s: &Status, z: f64) -> bool {
        if self.setting(201) == Some(1.0) {
            return s.feed.is_some_and(|f| f.1 > 0.0);
        }
        let up = self.setting(205).unwrap_or(0.0);
        let down = self.setting(206).unwrap_or(-2.0);
        (z - down).abs() < (z - up).abs()
    }

    fn status<T: Transport>(&mut self, p: &mut T, s: &Status) -> std::io::Result<()> {
        if let Some(w) = s.wco {
            self.wco = w;
        }
        if let Some(o) = s.overrides {
            self.overrides = o;
        }
        let Some(m) = s.machine_pos(self.wco) else {
            return Ok(());
        };
        let w = [m[0] - self.wco[0], m[1] - self.wco[1], m[2] - self.wco[2]];
        let mut down = self.pen_down(s, w[2]);
        if self.stopping.is_some()
            && (s.state == "Hold:0" || s.state == "Idle" || s.state.starts_with("Alarm"))
        {
            self.reset(p)?;
        }
        let mut job = Value::Null;
        let mut finished = false;
        if let (Some(r), Some(j)) = (&mut self.running, &self.job) {
            r.done_s = r.tracker.update(j, Pt::new(w[0], w[1]));
            // In a job the program says whether the pen draws (a file may
            // have no pen commands at all: then its feed moves draw).
            if let Some(mv) = j.moves.get(r.tracker.at()) {
                down = mv.kind == crate::toolpath::MoveKind::Draw;
            }
            if self.sender.done() && s.state == "Idle" {
                r.idle_reports += 1;
                // The first Idle may answer a poll sent before the last line.
                finished = r.idle_reports >= 2;
            }
            let total = j.total_s();
            let elapsed = r.started.elapsed().as_secs_f64();
            // Estimated machine time scaled by how fast it really goes (feed
            // overrides, a simulator running faster than real time).
            let pace = if r.done_s > 0.02 * total {
                elapsed / r.done_s
            } else {
                1.0
            };
            job = json!({
                "acked": r.acked,
                "lines": j.lines.len(),
                "done": if finished { 1.0 } else { (r.done_s / total.max(1e-9)).min(1.0) },
                "left_s": if finished { 0.0 } else { (total - r.done_s).max(0.0) * pace },
                "elapsed_s": elapsed,
            });
        }
        let point = [w[0], w[1], if down { 1.0 } else { 0.0 }];
        let moved = self.last != Some(point);
        self.last = Some(point);
        let msg = json!({
            "t": "status",
            "state": s.state,
            "pos": w,
            "mpos": m,
            "feed": s.feed.map_or(0.0, |f| f.0),
            "spindle": s.feed.map_or(0.0, |f| f.1),
            "ov": self.overrides,
            "pins": s.pins,
            "down": down,
            "point": if moved { json!(point) } else { Value::Null },
            "job": job,
        });
        {
            let mut snap = self.hub.snapshot();
            snap.pen = Pt::new(w[0], w[1]);
            if moved && snap.path.len() < PATH_KEEP {
                snap.path.push(point);
            }
            snap.status = Some(msg.clone());
        }
        self.hub.publish(&msg);
        if finished {
            if let Some(r) = self.running.take() {
                let t = r.started.elapsed().as_secs_f64();
                self.hub
                    .log(&format!("job done: {} lines in {t:.1} s", r.acked));
                self.hub
                    .publish(&json!({"t": "done", "ok": true, "why": ""}));
            }
        }
        Ok(())
    }
}
