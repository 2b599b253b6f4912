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
use inkstep_serial::stream::Line;
use serde_json::{json, Value};
use std::collections::{BTreeMap, VecDeque};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{broadcast, watch};

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
    /// Continues the job at a file line (None: where it stopped), the state
    /// before it rebuilt ([`crate::resume`]).
    Resume(Option<usize>),
    /// The firmware's estimate of the job `id`, computed after it was loaded:
    /// each move's end and the total, seconds.
    Estimate {
        id: u64,
        ends_s: Vec<f64>,
        total: f64,
    },
}

/// Status polls per second.
const STATUS_HZ: u64 = 20;
/// Log lines kept for browsers that join later.
const LOG_KEEP: usize = 100;
/// Path points kept (a long job at 20 reports a second: about 14 hours).
const PATH_KEEP: usize = 1_000_000;
/// Small events (log lines, answers, control changes) kept for browsers that
/// are behind; one further behind is dropped and reconnects.
pub const EVENTS: usize = 256;
/// Points (path) or moves (preview) in one message.
pub const CHUNK: usize = 2048;
/// About the largest message of [`CHUNK`] rows, bytes.
pub const CHUNK_BYTES: usize = CHUNK * 64;

/// A job as browsers are sent it: what it is, then its preview in pieces
/// (serialized once, shared by every browser).
pub struct JobView {
    pub head: Arc<str>,
    /// Binary messages: the generation (`u32` little-endian), then the rows.
    pub preview: Vec<axum::body::Bytes>,
}

/// What a browser joining now is sent first.
#[derive(Default)]
pub struct Snapshot {
    pub link: Option<Value>,
    pub settings: Option<Value>,
    pub fw: Option<Value>,
    pub alarm: Option<Value>,
    pub path: Vec<[f64; 3]>,
    pub log: VecDeque<Value>,
    /// The pen's work position, for planning a text or SVG from there.
    pub pen: Pt,
    /// The job's resume point (`{"t":"resumable","line":N}`).
    pub resumable: Option<Value>,
    /// The machine's settings (its `$$`), for time estimates.
    pub machine: inkstep_core::settings::Settings,
}

/// Shared between the link thread and the web handlers.
pub struct Hub {
    /// Small events, in order.
    pub out: broadcast::Sender<Arc<str>>,
    /// The latest status report (a browser behind skips the stale ones).
    pub status: watch::Sender<Option<Arc<str>>>,
    /// The job loaded.
    pub job: watch::Sender<Option<Arc<JobView>>>,
    pub snapshot: Mutex<Snapshot>,
}

impl Hub {
    pub fn new() -> Arc<Hub> {
        Arc::new(Hub {
            out: broadcast::channel(EVENTS).0,
            status: watch::channel(None).0,
            job: watch::channel(None).0,
            snapshot: Mutex::new(Snapshot::default()),
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

    /// The small messages that bring a new browser up to date (the job,
    /// the path and the status follow on their own).
    pub fn catch_up(&self) -> Vec<Arc<str>> {
        let s = self.snapshot();
        [&s.link, &s.fw, &s.alarm, &s.settings, &s.resumable]
            .into_iter()
            .flatten()
            .chain(s.log.iter())
            .map(|m| m.to_string().into())
            .collect()
    }

    /// The path's points from `from` on, at most [`CHUNK`] of them, as a
    /// message; None past its end (an empty path is one empty message).
    pub fn path_piece(&self, from: usize) -> Option<Arc<str>> {
        let s = self.snapshot();
        if from > 0 && from >= s.path.len() {
            return None;
        }
        let end = (from + CHUNK).min(s.path.len());
        let pts = s.path.get(from..end).unwrap_or(&[]);
        Some(
            json!({"t": "path", "from": from, "pts": pts})
                .to_string()
                .into(),
        )
    }

    fn set_status(&self, msg: Option<&Value>) {
        self.status.send_replace(msg.map(|m| m.to_string().into()));
    }

    /// Where the job loaded can be resumed, for browsers that join later.
    pub fn set_resumable(&self, msg: Value) {
        self.snapshot().resumable = Some(msg.clone());
        self.publish(&msg);
    }

    pub fn pen_and_machine(&self) -> (Pt, inkstep_core::settings::Settings) {
        let s = self.snapshot();
        (s.pen, s.machine.clone())
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
    /// The link's own `$I` (the version) after connecting.
    Info,
}

struct Running {
    /// The lines sent: the job's, or a resume's preamble and the job's rest.
    lines: Vec<Line>,
    /// Lines of the resume's preamble, and the index in the job's lines of
    /// the first one sent after it.
    pre: usize,
    offset: usize,
    /// The last `Ln:` the machine reported.
    ln: Option<u32>,
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
    /// Jobs loaded so far (the page tells a job's pieces from another's).
    generation: u64,
    /// The machine's state in its last report ("" when none or the port is away).
    state: String,
    /// The last alarm the machine raised.
    alarm: Option<u32>,
    /// A `$$` is on its way (none is sent again until it is answered).
    listing_sent: bool,
    /// The file line where the loaded job stopped, to resume from.
    resume_at: Option<usize>,
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
        generation: 0,
        state: String::new(),
        alarm: None,
        listing_sent: false,
        resume_at: None,
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
                link.listing_sent = false;
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
        if !up {
            // Nothing known about the machine now: no position or state to show.
            self.hub.set_status(None);
            self.state.clear();
            self.hub.snapshot().fw = None;
            self.last = None;
        }
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
                Ok(Request::Estimate { id, ends_s, total }) => self.estimated(id, ends_s, total),
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
        self.list_settings();
        self.sender.push(Origin::Info, "$I");
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
                    self.list_settings();
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
            Request::Resume(line) => self.resume_job(line),
            Request::Estimate { id, ends_s, total } => self.estimated(id, ends_s, total),
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
        self.listing_sent = false;
        self.stopping = None;
        Ok(())
    }

    fn load(&mut self, mut job: Job) {
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
        self.generation += 1;
        let head = json!({
            "t": "job",
            "gen": self.generation,
            "name": job.name,
            "lines": job.lines.len(),
            "est_s": job.total_s(),
            "moves": job.moves.len(),
            "left_out": left_out,
            "page": job.page.map(|(w, h)| [w, h]),
        });
        // The rows were made while the job was built; each piece is sent after
        // its generation, so a browser drops pieces of a job it no longer shows.
        let generation = self.generation as u32;
        let preview = std::mem::take(&mut job.preview_bin)
            .into_iter()
            .map(|rows| {
                let mut m = Vec::with_capacity(4 + rows.len());
                m.extend_from_slice(&generation.to_le_bytes());
                m.extend_from_slice(&rows);
                m.into()
            })
            .collect();
        self.hub.job.send_replace(Some(Arc::new(JobView {
            head: head.to_string().into(),
            preview,
        })));
        // The last run's drawing would hide the new preview.
        self.hub.snapshot().path.clear();
        self.last = None;
        self.hub.publish(&json!({"t": "clear"}));
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
        self.resume_at = None;
        self.hub
            .set_resumable(json!({"t": "resumable", "line": null, "gen": self.generation}));
    }

    /// The firmware's estimate of a job arrived: shown if it is still loaded.
    fn estimated(&mut self, id: u64, ends_s: Vec<f64>, total: f64) {
        let Some(job) = self.job.as_mut().filter(|j| j.id == id) else {
            return;
        };
        if ends_s.len() == job.ends_s.len() {
            job.ends_s = ends_s;
        }
        job.total = total;
        job.estimated = true;
        let m = json!({"t": "estimate", "gen": self.generation, "est_s": total});
        // Browsers that join later get it in the job's head.
        let view = self.hub.job.borrow().clone();
        if let Some(v) = view {
            if let Ok(mut head) = serde_json::from_str::<Value>(&v.head) {
                head["est_s"] = json!(total);
                self.hub.job.send_replace(Some(Arc::new(JobView {
                    head: head.to_string().into(),
                    preview: v.preview.clone(),
                })));
            }
        }
        self.hub.publish(&m);
        self.hub.log(&format!(
            "{}: the machine's estimate is {:.0} s",
            job.name, total
        ));
    }

    fn start_job(&mut self) {
        if self.running.is_some() {
            return;
        }
        let Some(job) = &self.job else {
            self.refuse_run("nothing loaded to run");
            return;
        };
        if self.state.starts_with("Alarm") {
            let why = match self.alarm {
                Some(n) => format!(
                    "Run refused: the machine is in alarm (ALARM:{n}, {}); unlock ($X) or home ($H) first",
                    alarm_text(n)
                ),
                None => "Run refused: the machine is in alarm; unlock ($X) or home ($H) first".into(),
            };
            self.refuse_run(&why);
            return;
        }
        if self.state.is_empty() {
            self.refuse_run("Run refused: no report from the machine yet");
            return;
        }
        let lines = job.lines.clone();
        let name = job.name.clone();
        self.start_lines(lines, 0, 0, Tracker::new());
        self.hub.log(&format!("running {name}"));
    }

    /// Continues the job at `line` (or where it stopped).
    fn resume_job(&mut self, line: Option<usize>) {
        if self.running.is_some() {
            return;
        }
        let Some(job) = &self.job else {
            self.refuse_run("nothing loaded to resume");
            return;
        };
        let Some(n) = line.or(self.resume_at) else {
            self.refuse_run("Resume refused: the job has not stopped anywhere; give a line");
            return;
        };
        if self.state.starts_with("Alarm") || self.state.is_empty() {
            self.refuse_run(
                "Resume refused: the machine is in alarm or not reporting; unlock ($X) or \
                 home ($H) first (after a power cut: home, or check the pen is at the origin)",
            );
            return;
        }
        let lines = match crate::resume::resume_lines_of(&job.lines, n, &self.core_settings()) {
            Ok(l) => l,
            Err(e) => {
                self.refuse_run(&format!("Resume refused: {e:#}"));
                return;
            }
        };
        let offset = job.lines.partition_point(|l| l.file_line < n);
        let pre = lines.len() - (job.lines.len() - offset);
        let first_move = job.moves.partition_point(|m| m.line < n);
        let name = job.name.clone();
        self.start_lines(lines, pre, offset, Tracker::starting_at(first_move));
        self.hub.log(&format!(
            "resuming {name} at line {n} ({pre} lines rebuild the state before it)"
        ));
    }

    fn start_lines(&mut self, lines: Vec<Line>, pre: usize, offset: usize, tracker: Tracker) {
        for (i, l) in lines.iter().enumerate() {
            self.sender.push(Origin::Job(i), l.text.as_str());
        }
        self.running = Some(Running {
            lines,
            pre,
            offset,
            ln: None,
            started: Instant::now(),
            acked: 0,
            tracker,
            done_s: 0.0,
            idle_reports: 0,
        });
        self.hub.snapshot().path.clear();
        self.last = None;
        self.hub.publish(&json!({"t": "clear"}));
    }

    /// The machine's settings as the core reads them (defaults for the rest).
    fn core_settings(&self) -> inkstep_core::settings::Settings {
        self.hub.pen_and_machine().1
    }

    fn refuse_run(&self, why: &str) {
        self.hub.log(why);
        self.hub
            .publish(&json!({"t": "done", "ok": false, "why": why}));
    }

    fn abort_job(&mut self, why: &str) {
        if let (Some(r), Some(job)) = (&self.running, &self.job) {
            // Where to resume: the line the machine reported (Ln:), else the
            // line of the move the pen was last seen on.
            let by_ln = r.ln.and_then(|n| {
                job.lines
                    .iter()
                    .find(|l| crate::resume::n_word(&l.text) == Some(n))
                    .map(|l| l.file_line)
            });
            let by_pos = job.moves.get(r.tracker.at()).map(|m| m.line);
            if let Some(n) = by_ln.or(by_pos) {
                self.resume_at = Some(n);
                self.hub
                    .set_resumable(json!({"t": "resumable", "line": n, "gen": self.generation}));
            }
        }
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
                    let line = self
                        .running
                        .as_ref()
                        .and_then(|r| r.lines.get(i))
                        .map_or(0, |l| l.file_line);
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
                    self.list_settings();
                }
            }
            Event::Answered(Origin::Info, _) => {}
            Event::Answered(Origin::Listing, Answer::Ok) => {
                self.listing_sent = false;
                self.publish_settings();
            }
            Event::Answered(Origin::Listing, Answer::Error(n)) => {
                self.listing_sent = false;
                // Refused (error:8 while moving): the table shown stays.
                self.listing.clear();
                self.hub.log(&format!(
                    "$$: error:{n} ({}); the settings shown are unchanged",
                    error_text(n)
                ));
            }
            Event::Reply(Reply::Setting(n, v)) => {
                self.listing.insert(n, v);
            }
            Event::Reply(Reply::Status(s)) => self.status(p, &s)?,
            Event::Reply(Reply::Alarm(n)) => {
                self.alarm = Some(n);
                let m = json!({"t": "alarm", "n": n, "text": alarm_text(n)});
                self.hub.snapshot().alarm = Some(m.clone());
                self.hub.publish(&m);
                self.abort_job(&format!("ALARM:{n} ({})", alarm_text(n)));
                self.hub.log(&format!("ALARM:{n} ({})", alarm_text(n)));
            }
            Event::Reply(Reply::Welcome(w)) => {
                // The controller restarted: whatever was in its buffer is gone
                // (its settings may have changed too: read them again).
                self.sender.clear();
                self.listing_sent = false;
                self.stopping = None;
                self.abort_job("the controller restarted");
                self.hub.log(&w);
                self.set_firmware(&w);
                self.list_settings();
            }
            Event::Reply(Reply::Feedback(f)) => {
                if let Some(v) = f.strip_prefix("VER:") {
                    self.set_firmware(&format!("Grbl {}", v.trim_end_matches(':')));
                }
                self.hub.log(&format!("[{f}]"));
            }
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
        // The firmware's defaults for anything the listing leaves out.
        let mut machine = inkstep_core::settings::Settings::default();
        for (&n, v) in &self.settings {
            if let Ok(v) = v.trim().parse::<f32>() {
                let _ = machine.set(n, v);
            }
        }
        let m = json!({"t": "settings", "list": list});
        let mut s = self.hub.snapshot();
        s.machine = machine;
        s.settings = Some(m.clone());
        drop(s);
        self.hub.publish(&m);
    }

    /// Reads the `$$` table (into `listing`, published when answered).
    fn list_settings(&mut self) {
        self.listing_sent = true;
        self.sender.push(Origin::Listing, "$$");
    }

    /// The firmware's name and version, shown in the page.
    fn set_firmware(&self, text: &str) {
        let text = text.split(" [").next().unwrap_or(text).trim();
        let m = json!({"t": "fw", "text": text});
        self.hub.snapshot().fw = Some(m.clone());
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
        self.state.clone_from(&s.state);
        // No table yet (the first `$$` was lost to a reset or refused): ask
        // again once the machine is at rest.
        if !self.listing_sent && s.state == "Idle" && self.hub.snapshot().settings.is_none() {
            self.list_settings();
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
            if s.line.is_some() {
                r.ln = s.line;
            }
            // The job's lines sent (a resume's preamble counts as none).
            let sent = r.acked + self.sender.in_flight();
            let sent = r.offset + sent.saturating_sub(r.pre);
            r.done_s = r.tracker.update(j, Pt::new(w[0], w[1]), sent);
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
        }
        self.hub.set_status(Some(&msg));
        if finished {
            if let Some(r) = self.running.take() {
                let t = r.started.elapsed().as_secs_f64();
                self.hub
                    .log(&format!("job done: {} lines in {t:.1} s", r.acked));
                self.hub
                    .publish(&json!({"t": "done", "ok": true, "why": ""}));
                self.resume_at = None;
                self.hub
                    .set_resumable(json!({"t": "resumable", "line": null, "gen": self.generation}));
            }
        }
        Ok(())
    }
}
