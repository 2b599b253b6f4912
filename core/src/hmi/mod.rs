//! The standalone user interface: menus, manual jog, the drawing modes of the lab report,
//! and the machine feedback (beeps), as one pure state machine. (The busy LED follows
//! the motion millisecond by millisecond: `stepper::idle`.)
//!
//! The HMI never touches the machine. Its inputs are explicit: keypad events
//! ([`Hmi::key`]) and a [`Snapshot`] of the machine on every call, plus the
//! time in ms; its outputs are [`Action`]s the integrator carries out in order (queue
//! these moves, start/stop a jog, feed hold, abort, beep, ...). The pages the screens
//! draw are exposed read-only ([`Hmi::page`] and friends). So it runs unchanged in the
//! firmware's keypad task, in the simulator and in host tests.
//!
//! The report's two-level structure (main loop picks a mode, each mode loops until its
//! exit key) becomes a [`Page`] enum: each page handles its keys and returns to the menu
//! by replacing itself, never by blocking.

pub mod buzzer;
pub mod entry;
pub mod fixed;
pub mod io;
pub mod job;
pub mod menu;
pub mod page;
pub mod text;

pub use io::{alarm_text, Action, Actions, Beep, Config, MachineState, Snapshot};
pub use menu::{MachineItem, MenuItem, MACHINE_LINES, MACHINE_MENU, MENU, MENU_LINES};
pub use page::{JogPage, Page, PromptView, RunPage, RunPhase, Toast, DIR_HISTORY, PROMPT_MESSAGE};

use crate::fmath;
use crate::keypad::{Key, KeyEvent, KeyKind};
use crate::motion::{Feed, Move, Path, StepPos, X, Y, Z};
use crate::pending::Work;
use entry::{FieldInput, Form, FormKind, FormMemory, DEFAULT_PARAMS};
use job::Job;
use text::Text;

/// Jog speeds selectable with speed + / speed -.
pub const JOG_SPEEDS: [f32; 7] = [50.0, 100.0, 200.0, 400.0, 800.0, 1500.0, 3000.0];
const JOG_SPEED_DEFAULT: usize = 3;
/// Draw speed range and step on the status page.
const DRAW_FEED_MIN: f32 = 50.0;
const DRAW_FEED_MAX: f32 = 3000.0;
const DRAW_FEED_STEP: f32 = 50.0;
/// How long the boot screen shows and messages stay.
pub const BOOT_MS: u32 = 1500;
const TOAST_MS: u32 = 2500;
/// A job counts as stopped early if the machine sits idle this long short of its end.
const SETTLE_MS: u32 = 1000;

/// The HMI state machine. The LCD task draws from a clone taken under a short lock.
#[derive(Clone, Debug)]
pub struct Hmi {
    cfg: Config,
    page: Page,
    boot_ms: u32,
    params: FormMemory,
    last_job: Option<Job>,
    jog_speed: usize,
    draw_feed: f32,
    /// The latest distinct feed directions, oldest first: the first `ndirs`.
    dirs: [[i8; 2]; DIR_HISTORY],
    ndirs: u8,
    alarm_latched: bool,
    toast: Option<Toast>,
    /// What the machine waits for the user to do (M0, M6), shown over the page.
    prompt: Option<PromptView>,
    /// Bumped whenever what the screens show of the HMI may have changed (every key
    /// event, new settings, and each change [`Hmi::tick`] makes to the page or the
    /// message): the LCD skips a refresh when neither this nor the machine status
    /// changed (`screens::Screens::render`). A counter rather than a comparison of
    /// the whole state, which costs the image over a kilobyte of flash and a second
    /// copy of the state in RAM.
    revision: u32,
}

fn dist_mm(a: StepPos, b: StepPos, spmm: [f32; 3]) -> f32 {
    let dx = (b[X].wrapping_sub(a[X])) as f32 / spmm[X];
    let dy = (b[Y].wrapping_sub(a[Y])) as f32 / spmm[Y];
    fmath::hypot(dx, dy)
}

/// Queue a rapid pen-axis move to `z_mm` where X and Y stand; false (and nothing
/// queued) if out of step range.
fn pen_move(st: &Snapshot, z_mm: f32, steps_per_mm: f32, out: &mut Actions) -> bool {
    let Some(z) = fixed::round_checked(z_mm * steps_per_mm) else {
        return false;
    };
    let lift = Move {
        target: [st.pos[X], st.pos[Y], z],
        path: Path::Line,
        feed: Feed::Rapid,
        line: 0,
    };
    push(out, Action::Queue(lift));
    true
}

/// `msg` as LCD text: what fits, anything but printable ASCII as `?`.
fn ascii_text<const N: usize>(msg: &[u8]) -> Text<N> {
    let mut t = Text::new();
    for &b in msg {
        if !t.push_ascii(if b.is_ascii_graphic() || b == 32 {
            b
        } else {
            63
        }) {
            break;
        }
    }
    t
}

/// Append an action to a response.
fn push(out: &mut Actions, a: Action) {
    // Capacity covers the largest single response (a job start); never silently
    // exceeded by construction, checked here rather than panicking.
    let _ = out.push(a);
}

impl Hmi {
    pub fn new(cfg: Config, now_ms: u32) -> Self {
        Hmi {
            cfg,
            page: Page::Boot,
            boot_ms: now_ms,
            params: DEFAULT_PARAMS,
            last_job: None,
            jog_speed: JOG_SPEED_DEFAULT,
            draw_feed: cfg.draw_feed_mm_min,
            dirs: [[0; 2]; DIR_HISTORY],
            ndirs: 0,
            alarm_latched: false,
            toast: None,
            prompt: None,
            revision: 0,
        }
    }

    /// The timed work [`Hmi::tick`] still has: the boot screen or a message to take
    /// down, a job to follow. Otherwise it only follows the machine, which does not
    /// change while no layer has work.
    pub fn pending(&self) -> Option<Work> {
        let following = |run: &RunPage| !matches!(run.phase, RunPhase::Done { .. });
        if self.toast.is_some() || matches!(&self.page, Page::Boot) {
            Some(Work::HmiTimer)
        } else if matches!(&self.page, Page::Run(run) if following(run)) {
            Some(Work::HmiJob)
        } else {
            None
        }
    }

    /// Test support: hold `w` if it is the HMI's kind of work (`on`), or none of it
    /// (a menu, no message); false for the other layers' kinds.
    #[cfg(test)]
    pub(crate) fn set_work(&mut self, w: Work, on: bool) -> bool {
        self.toast = None;
        self.page = Page::Menu { sel: 0 };
        match (w, on) {
            (Work::HmiTimer, true) => self.page = Page::Boot,
            (Work::HmiJob, true) => {
                self.page = Page::Run(RunPage {
                    job: Job::Line { dx: 1.0, dy: 0.0 },
                    start: [0; 3],
                    end: [80, 0, 0],
                    started_ms: 0,
                    phase: RunPhase::Running,
                    traveled_mm: 0.0,
                    length_mm: 1.0,
                    last_pos: [0; 3],
                    idle_since: None,
                })
            }
            (Work::HmiTimer | Work::HmiJob, false) => {}
            _ => return false,
        }
        true
    }

    /// Changes whenever what the screens show of the HMI may have changed.
    pub fn revision(&self) -> u32 {
        self.revision
    }
    fn changed(&mut self) {
        self.revision = self.revision.wrapping_add(1);
    }

    pub fn page(&self) -> &Page {
        &self.page
    }
    pub fn config(&self) -> &Config {
        &self.cfg
    }
    /// New machine settings (e.g. after `$100=`); also resets the draw speed to the
    /// configured one. Takes effect for the next job.
    pub fn set_config(&mut self, cfg: Config) {
        self.changed();
        self.cfg = cfg;
        self.draw_feed = cfg.draw_feed_mm_min;
    }
    /// The machine's prompt (M0, M6), drawn over the page.
    pub fn prompt(&self) -> Option<&PromptView> {
        self.prompt.as_ref()
    }
    /// The machine waits for the user, or no longer does: `pen` for M6, `None` for
    /// M0, with the last `(MSG, ...)` text.
    pub fn set_prompt(&mut self, prompt: Option<(Option<u8>, &[u8])>) {
        let view = prompt.map(|(pen, msg)| PromptView {
            pen,
            message: ascii_text(msg),
        });
        if view != self.prompt {
            self.prompt = view;
            self.changed();
        }
    }
    /// A `(MSG, ...)` from the G-code: shown as a message for a while.
    pub fn show_message(&mut self, msg: &[u8], now_ms: u32) {
        self.show(ascii_text(msg), now_ms);
    }
    pub fn toast(&self) -> Option<&Text<28>> {
        self.toast.as_ref().map(|t| &t.text)
    }
    pub fn jog_speed(&self) -> f32 {
        JOG_SPEEDS.get(self.jog_speed).copied().unwrap_or(100.0)
    }
    pub fn draw_feed(&self) -> f32 {
        self.draw_feed
    }
    pub fn last_job(&self) -> Option<Job> {
        self.last_job
    }
    /// The latest distinct feed directions, oldest first.
    pub fn feed_dirs(&self) -> impl DoubleEndedIterator<Item = &[i8; 2]> {
        self.dirs
            .get(..usize::from(self.ndirs))
            .unwrap_or(&[])
            .iter()
    }
    /// Whether the pen is down (pen axis nearer the down than the up position).
    pub fn pen_is_down(&self, st: &Snapshot) -> bool {
        let z = st.pos[Z] as f32 / self.cfg.steps_per_mm[Z];
        (z - self.cfg.pen_down_mm).abs() < (z - self.cfg.pen_up_mm).abs()
    }
    /// Position in mm.
    pub fn pos_mm(&self, st: &Snapshot) -> [f32; 3] {
        let mut p = [0.0; 3];
        for ((mm, &steps), &spmm) in p.iter_mut().zip(&st.pos).zip(&self.cfg.steps_per_mm) {
            *mm = steps as f32 / spmm;
        }
        p
    }

    fn say(&mut self, text: &str, now_ms: u32) {
        self.show(Text::truncated(text), now_ms);
    }

    /// [`Hmi::say`] for a message built at run time: taken as it is, not through
    /// `&str` (which would check its UTF-8 again).
    fn show(&mut self, text: Text<28>, now_ms: u32) {
        self.changed();
        self.toast = Some(Toast {
            text,
            until_ms: now_ms.wrapping_add(TOAST_MS),
        });
    }

    fn error(&mut self, title: &'static str, text: &'static str, out: &mut Actions) {
        self.page = Page::Error { title, text };
        push(out, Action::Beep(Beep::Error));
    }

    /// Can a new motion command start now? Otherwise shows why.
    fn ready(&mut self, st: &Snapshot, out: &mut Actions) -> bool {
        let settled = st.state == MachineState::Idle && st.queue_empty;
        self.allowed(st, !settled, out)
    }

    /// Unless the machine is in alarm or `busy`, true; otherwise shows why (the alarm
    /// first) and false. The one place that words a refused command.
    fn allowed(&mut self, st: &Snapshot, busy: bool, out: &mut Actions) -> bool {
        let (title, text) = if matches!(st.state, MachineState::Alarm(_)) {
            ("Alarm", "Unlock or home first")
        } else if busy {
            ("Busy", "Machine is moving")
        } else {
            return true;
        };
        self.error(title, text, out);
        false
    }

    /// Handle one keypad event.
    ///
    /// This and [`Hmi::tick`] are the HMI's entry points, kept out of line so that their
    /// working state is gone before the controller applies their actions (through the
    /// machine and the planner, the deepest path of the keypad and protocol tasks; the
    /// RAM budget needs it: docs/architecture.md, "Kept for RAM or speed").
    #[inline(never)]
    pub fn key(&mut self, ev: KeyEvent, st: &Snapshot, now_ms: u32) -> Actions {
        // Keys are rare: any of them counts as a change.
        self.changed();
        let mut out = Actions::new();
        let press = ev.kind == KeyKind::Press;
        let repeat = ev.kind == KeyKind::Repeat;
        if press && ev.key == Key::Enter && self.prompt.is_some() {
            // D answers the machine's prompt: cycle start.
            push(&mut out, Action::Resume);
            return out;
        }
        match &mut self.page {
            Page::Boot => {
                if press {
                    self.page = Page::Menu { sel: 0 };
                }
            }
            // The main menu and the machine submenu share one list navigation.
            Page::Menu { sel } | Page::Machine { sel } => {
                let sel = *sel;
                let main = matches!(self.page, Page::Menu { .. });
                let n = if main { MENU.len() } else { MACHINE_MENU.len() };
                let at = |sel: usize| {
                    if main {
                        Page::Menu { sel }
                    } else {
                        Page::Machine { sel }
                    }
                };
                let chosen = match ev.key {
                    Key::Up if press || repeat => {
                        self.page = at((sel + n - 1) % n);
                        None
                    }
                    Key::Down if press || repeat => {
                        self.page = at((sel + 1) % n);
                        None
                    }
                    Key::Back if press && !main => {
                        self.page = Page::Menu { sel: 8 };
                        None
                    }
                    Key::Enter if press => Some(sel),
                    // Both menus' hotkeys are 1, 2, ... 9, 0 in order.
                    Key::Digit(d) if press => Some((usize::from(d) + 9) % 10).filter(|&i| i < n),
                    _ => None,
                };
                if let Some(i) = chosen {
                    if main {
                        self.page = Page::Menu { sel: i };
                        self.open(i, st, now_ms, &mut out);
                    } else {
                        self.machine(i, st, now_ms, &mut out);
                    }
                }
            }
            Page::Jog(_) => self.jog_key(ev, st, now_ms, &mut out),
            Page::Form(_) => self.form_key(ev, now_ms, &mut out),
            Page::Preview { job, form } => {
                let (job, form) = (*job, *form);
                if press {
                    match ev.key {
                        Key::Enter => self.start(job, st, now_ms, &mut out),
                        Key::Back => match form {
                            Some(kind) => self.open_form(kind),
                            None => self.page = Page::Menu { sel: 0 },
                        },
                        _ => {}
                    }
                }
            }
            Page::Run(run) => {
                if press {
                    match (run.phase, ev.key) {
                        (RunPhase::Running, Key::Enter) => {
                            if st.state == MachineState::Hold {
                                push(&mut out, Action::Resume);
                            } else {
                                push(&mut out, Action::FeedHold);
                            }
                        }
                        (RunPhase::Running, Key::Back) => {
                            push(&mut out, Action::Abort);
                            run.phase = RunPhase::Stopping;
                        }
                        (RunPhase::Done { .. }, Key::Enter | Key::Back) => {
                            self.page = Page::Menu { sel: 0 };
                        }
                        _ => {}
                    }
                }
            }
            Page::Status => {
                if press || repeat {
                    match ev.key {
                        Key::Up => {
                            self.draw_feed = (self.draw_feed + DRAW_FEED_STEP).min(DRAW_FEED_MAX)
                        }
                        Key::Down => {
                            self.draw_feed = (self.draw_feed - DRAW_FEED_STEP).max(DRAW_FEED_MIN)
                        }
                        Key::Back | Key::Enter if press => self.page = Page::Menu { sel: 9 },
                        _ => {}
                    }
                }
            }
            Page::Alarm { .. } => {
                if press {
                    match ev.key {
                        Key::Enter => push(&mut out, Action::Unlock),
                        Key::Back => self.page = Page::Menu { sel: 0 },
                        _ => {}
                    }
                }
            }
            Page::Error { .. } => {
                if press {
                    self.page = Page::Menu { sel: 0 };
                }
            }
        }
        out
    }

    /// Open main menu entry `i`.
    fn open(&mut self, i: usize, st: &Snapshot, now_ms: u32, out: &mut Actions) {
        let Some((_, item)) = MENU.get(i).copied() else {
            return;
        };
        match item {
            MenuItem::Jog => {
                let busy = st.state.moving() && st.state != MachineState::Jog;
                if self.allowed(st, busy, out) {
                    self.page = Page::Jog(JogPage {
                        active: None,
                        last_dir: [0, 0],
                    });
                }
            }
            MenuItem::Draw(kind) => self.open_form(kind),
            MenuItem::Pen => {
                if self.ready(st, out) {
                    self.toggle_pen(st, now_ms, out);
                }
            }
            MenuItem::Replay => match self.last_job {
                Some(job) => self.page = Page::Preview { job, form: None },
                None => self.say("No job drawn yet", now_ms),
            },
            MenuItem::Machine => self.page = Page::Machine { sel: 0 },
            MenuItem::Status => self.page = Page::Status,
        }
    }

    /// The parameter form of `kind`, filled with the values last drawn (or the defaults).
    fn open_form(&mut self, kind: FormKind) {
        self.page = Page::Form(Form::new(kind, &self.params[kind.index()]));
    }

    fn machine(&mut self, i: usize, st: &Snapshot, now_ms: u32, out: &mut Actions) {
        let Some((_, item)) = MACHINE_MENU.get(i).copied() else {
            return;
        };
        self.page = Page::Machine { sel: i };
        if !self.ready(st, out) {
            return;
        }
        match item {
            MachineItem::GoOrigin => {
                let p = self.pos_mm(st);
                self.start(
                    Job::Travel {
                        dx: -p[X],
                        dy: -p[Y],
                    },
                    st,
                    now_ms,
                    out,
                );
            }
            MachineItem::SetOrigin => {
                push(out, Action::SetOrigin);
                self.say("Origin set here", now_ms);
            }
            MachineItem::Home => {
                push(out, Action::Home);
                self.say("Homing...", now_ms);
            }
        }
    }

    fn toggle_pen(&mut self, st: &Snapshot, now_ms: u32, out: &mut Actions) {
        let down = !self.pen_is_down(st);
        let z_mm = if down {
            self.cfg.pen_down_mm
        } else {
            self.cfg.pen_up_mm
        };
        if !pen_move(st, z_mm, self.cfg.steps_per_mm[Z], out) {
            return;
        }
        self.say(if down { "Pen down" } else { "Pen up" }, now_ms);
    }

    fn jog_key(&mut self, ev: KeyEvent, st: &Snapshot, now_ms: u32, out: &mut Actions) {
        let Page::Jog(jog) = &mut self.page else {
            return;
        };
        let mut jog = *jog;
        // Jogging (re)starts in this direction at the current speed, after the match.
        let mut start = None;
        match (ev.kind, ev.key) {
            (KeyKind::Press, k) if k.jog_dir().is_some() => {
                let Some(dir) = k.jog_dir() else { return };
                if !self.allowed(st, false, out) {
                    return;
                }
                if jog.active.is_some() {
                    push(out, Action::JogStop);
                }
                jog.active = Some((k, dir));
                jog.last_dir = dir;
                start = Some(dir);
            }
            (KeyKind::Release, k) if jog.active.map(|(held, _)| held) == Some(k) => {
                push(out, Action::JogStop);
                jog.active = None;
            }
            // Speed +/- act once per press (Repeat is ignored): the report's problem 3.
            (KeyKind::Press, Key::Up | Key::Down) => {
                self.jog_speed = if ev.key == Key::Up {
                    (self.jog_speed + 1).min(JOG_SPEEDS.len() - 1)
                } else {
                    self.jog_speed.saturating_sub(1)
                };
                start = jog.active.map(|(_, dir)| dir);
            }
            (KeyKind::Press, Key::Digit(5)) => {
                if jog.active.is_none() && self.ready(st, out) {
                    self.toggle_pen(st, now_ms, out);
                }
                if !matches!(self.page, Page::Jog(_)) {
                    return;
                }
            }
            (KeyKind::Press, Key::Back) => {
                if jog.active.is_some() {
                    push(out, Action::JogStop);
                }
                self.page = Page::Menu { sel: 0 };
                return;
            }
            _ => {}
        }
        if let Some(dir) = start {
            let feed_mm_min = self.jog_speed();
            push(out, Action::JogStart { dir, feed_mm_min });
        }
        self.page = Page::Jog(jog);
    }

    fn form_key(&mut self, ev: KeyEvent, now_ms: u32, out: &mut Actions) {
        if ev.kind == KeyKind::Release {
            return;
        }
        let repeat = ev.kind == KeyKind::Repeat;
        let Page::Form(form) = &mut self.page else {
            return;
        };
        let kind = form.kind;
        let Some(field) = form.current() else {
            return;
        };
        match field.key(ev.key, repeat) {
            FieldInput::Edited => return,
            FieldInput::Cancel => {
                // The drawing modes follow Jog in the menu, in form order.
                self.page = Page::Menu {
                    sel: kind.index() + 1,
                };
                return;
            }
            FieldInput::Ignored => {}
        }
        let forward = match ev.key {
            Key::Up => false,
            Key::Down => true,
            Key::Enter if !repeat => true,
            _ => return,
        };
        if let Err(msg) = field.commit() {
            self.show(msg, now_ms);
            push(out, Action::Beep(Beep::Error));
            return;
        }
        if ev.key == Key::Enter && form.is_last() {
            let job = form.job();
            let values = form.values();
            // Planned once from the origin only to check it: into `out` (empty here:
            // nothing is pushed before a commit succeeds) and dropped again, so that
            // no second action list sits on the keypad task's stack.
            let before = out.len();
            let checked = job.plan([0; 3], &self.cfg, out);
            out.truncate(before);
            match checked {
                Ok(_) => {
                    if let Some(slot) = self.params.get_mut(kind.index()) {
                        *slot = values;
                    }
                    self.page = Page::Preview {
                        job,
                        form: Some(kind),
                    };
                }
                Err(e) => {
                    self.say(e.message(), now_ms);
                    push(out, Action::Beep(Beep::Error));
                }
            }
        } else if forward {
            form.cur = (form.cur + 1).min(form.fields().len().saturating_sub(1));
        } else {
            form.cur = form.cur.saturating_sub(1);
        }
    }

    /// Queue a job's moves and show it running.
    fn start(&mut self, job: Job, st: &Snapshot, now_ms: u32, out: &mut Actions) {
        if !self.ready(st, out) {
            return;
        }
        let cfg = Config {
            draw_feed_mm_min: self.draw_feed,
            ..self.cfg
        };
        match job.plan(st.pos, &cfg, out) {
            Ok(end) => {
                if job.draws() {
                    self.last_job = Some(job);
                }
                self.ndirs = 0;
                self.page = Page::Run(RunPage {
                    job,
                    start: st.pos,
                    end,
                    started_ms: now_ms,
                    phase: RunPhase::Running,
                    traveled_mm: 0.0,
                    length_mm: job.length_mm(),
                    last_pos: st.pos,
                    idle_since: None,
                });
            }
            Err(e) => self.error("Cannot draw", e.message(), out),
        }
    }

    /// Follow the machine: call every refresh (e.g. 10-20 Hz) with a fresh snapshot.
    /// Out of line, as [`Hmi::key`].
    #[inline(never)]
    pub fn tick(&mut self, st: &Snapshot, now_ms: u32) -> Actions {
        let mut out = Actions::new();
        // Teaching view: remember each new feed direction.
        if st.dir != [0, 0] && self.feed_dirs().next_back() != Some(&st.dir) {
            let n = usize::from(self.ndirs);
            if let Some(next) = self.dirs.get_mut(n) {
                *next = st.dir;
                self.ndirs += 1;
            } else {
                // Full: the oldest drops out.
                self.dirs.copy_within(1.., 0);
                if let Some(last) = self.dirs.last_mut() {
                    *last = st.dir;
                }
            }
        }
        if let Some(t) = &self.toast {
            if (now_ms.wrapping_sub(t.until_ms) as i32) >= 0 {
                self.toast = None;
                self.changed();
            }
        }
        // Alarms take over the screen once per occurrence.
        match st.state {
            MachineState::Alarm(code) => {
                if !self.alarm_latched {
                    self.alarm_latched = true;
                    self.page = Page::Alarm { code };
                    self.changed();
                    push(&mut out, Action::Beep(Beep::Alarm));
                }
            }
            _ => {
                self.alarm_latched = false;
                if matches!(self.page, Page::Alarm { .. }) {
                    self.page = Page::Menu { sel: 0 };
                    self.say("Alarm cleared", now_ms);
                }
            }
        }
        let spmm = self.cfg.steps_per_mm;
        let mut stopped_at = None;
        match &mut self.page {
            Page::Boot if now_ms.wrapping_sub(self.boot_ms) >= BOOT_MS => {
                self.page = Page::Menu { sel: 0 };
                self.changed();
            }
            // A jog ended by something else (alarm, reset) is no longer held.
            Page::Jog(jog)
                if jog.active.is_some()
                    && !matches!(st.state, MachineState::Jog | MachineState::Idle) =>
            {
                jog.active = None;
                self.changed();
            }
            Page::Run(run) => {
                let settled = st.state == MachineState::Idle && st.queue_empty;
                match run.phase {
                    RunPhase::Running => {
                        run.traveled_mm += dist_mm(run.last_pos, st.pos, spmm);
                        run.last_pos = st.pos;
                        if settled {
                            let ms = now_ms.wrapping_sub(run.started_ms);
                            if st.pos == run.end {
                                run.phase = RunPhase::Done { ms, complete: true };
                                push(&mut out, Action::Beep(Beep::Done));
                            } else {
                                let since = *run.idle_since.get_or_insert(now_ms);
                                if now_ms.wrapping_sub(since) >= SETTLE_MS {
                                    run.phase = RunPhase::Done {
                                        ms,
                                        complete: false,
                                    };
                                    push(&mut out, Action::Beep(Beep::Error));
                                }
                            }
                        } else {
                            run.idle_since = None;
                        }
                    }
                    RunPhase::Stopping => {
                        if settled {
                            stopped_at = Some(run.job.draws());
                        }
                    }
                    RunPhase::Done { .. } => {}
                }
            }
            _ => {}
        }
        if let Some(draws) = stopped_at {
            // Stopped cleanly: lift the pen where it stands, report the position.
            if draws {
                pen_move(st, self.cfg.pen_up_mm, spmm[Z], &mut out);
            }
            let p = self.pos_mm(st);
            let mut msg = Text::new();
            msg.push_str("Stopped X");
            msg.push_fixed(p[X], 1);
            msg.push_str(" Y");
            msg.push_fixed(p[Y], 1);
            self.page = Page::Menu { sel: 0 };
            self.show(msg, now_ms);
        }
        out
    }
}

#[cfg(test)]
mod tests;
