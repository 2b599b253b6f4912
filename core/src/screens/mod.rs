//! The LCD pages: what each [`Page`] of the HMI looks like on the 128x64 ST7920, painted
//! straight into the [`FrameBuffer`].
//!
//! [`Screens`] is retained-mode on purpose: when the page changes it clears and draws
//! the static parts (frames, labels, the curve preview) once; on every later refresh it
//! repaints only the live cells (coordinates, speed, progress, the trace's new segment,
//! the pen ticks) in place. With the dirty-tracking [`framebuffer::FrameBuffer`] that
//! means a refresh while drawing sends a few hundred bytes, not the whole screen (see
//! [`st7920`] for the SPI budget). The small state it keeps (page identity, the preview
//! fit, the pen trace, the last arrow and ticks) is what the retained drawing needs.
//!
//! Fonts are in [`fonts`]; shared pieces are in [`widgets`]. The frame buffer is the
//! only drawing target (no generic `DrawTarget` code in the firmware).

pub mod fonts;
pub mod framebuffer;
pub mod plot;
pub mod st7920;
pub mod widgets;

use core::convert::Infallible;

use crate::fmath;
use crate::hmi::fixed;
use crate::hmi::job::Job;
use crate::hmi::text::Text;
use crate::hmi::{alarm_text, Hmi, MachineState, Page, RunPhase, Snapshot};
use crate::hmi::{MACHINE_LINES, MENU_LINES};
use crate::motion::{X, Y};
use framebuffer::FrameBuffer;
use plot::{Area, Plot, Trace};
use widgets::{arrow, bottom_line, progress, put, title_bar, Cell, Px};

/// Rows of a list or form page (below the title, above the bottom line).
const ROWS: usize = 4;

/// The y of list / form row `i` (11, 21, 31, 41).
const fn row_y(i: usize) -> i32 {
    11 + 10 * i as i32
}
/// The preview / trace box of the drawing page.
const RUN_BOX: Area = [2, 11, 72, 42];
/// The preview box of the "ready to draw" page.
const PREVIEW_BOX: Area = [0, 11, 80, 43];

/// Which page (and which instance of it) is on the screen: a page number and what
/// tells its instances apart (form kind, the previewed job's parameters as bits, run
/// start time, alarm code). Compared as plain words, no float comparisons.
type PageKey = [u32; 6];

fn page_key(page: &Page) -> PageKey {
    match page {
        Page::Boot => [0; 6],
        Page::Menu { .. } => [1, 0, 0, 0, 0, 0],
        Page::Machine { .. } => [2, 0, 0, 0, 0, 0],
        Page::Jog(_) => [3, 0, 0, 0, 0, 0],
        Page::Form(f) => [4, f.kind.index() as u32, 0, 0, 0, 0],
        Page::Preview { job, .. } => {
            let (kind, v) = job.words();
            [5, kind, v[0], v[1], v[2], v[3]]
        }
        Page::Run(r) => [6, r.started_ms, 0, 0, 0, 0],
        Page::Status => [7, 0, 0, 0, 0, 0],
        Page::Alarm { code } => [8, u32::from(*code), 0, 0, 0, 0],
        Page::Error { .. } => [9, 0, 0, 0, 0, 0],
    }
}

/// One line of text being built.
type TextLine = Text<32>;

/// Line templates: ASCII text with value slots. `FIX + d` is the next value with d
/// (0..=3) decimals, `UINT + w` the next value as an unsigned integer right-aligned in
/// w (0..=7) characters, `AXIS + w` the next value with 2 decimals right-aligned in w
/// characters. One routine builds every line from its template instead of a call per
/// piece at each place.
const FIX: u8 = 1;
const UINT: u8 = 8;
const AXIS: u8 = 16;

/// Build `tpl` with `vals` into `l` (cleared first); its bytes.
fn fill<'a>(l: &'a mut TextLine, tpl: &[u8], vals: &[f32]) -> &'a [u8] {
    l.clear();
    let mut v = vals.iter().copied();
    for &b in tpl {
        // (decimals, or none for an integer; width)
        let (decimals, width) = match b {
            FIX..UINT => (Some((b - FIX).min(3)), 0),
            UINT..AXIS => (None, b - UINT),
            AXIS..24 => (Some(2), b - AXIS),
            _ => {
                l.push_ascii(b);
                continue;
            }
        };
        let x = v.next().unwrap_or(0.0);
        let (num, decimals) = match decimals {
            Some(d) => (fixed::scaled(x, d), d),
            None => (Some((false, x as u32)), 0),
        };
        l.push_number(num, decimals, usize::from(width));
    }
    l.bytes()
}

/// Put the line of template `tpl` with `vals` in cell `c`.
fn put_line(fb: &mut FrameBuffer, c: Cell, l: &mut TextLine, tpl: &[u8], vals: &[f32]) {
    put(fb, c, fill(l, tpl, vals));
}

/// Append "+X-Y" for a direction; "--" for none.
fn push_dir(l: &mut TextLine, dir: [i8; 2]) {
    let at = l.len();
    for (v, axis) in [(dir[0], b'X'), (dir[1], b'Y')] {
        if v != 0 {
            l.push_ascii(if v > 0 { b'+' } else { b'-' });
            l.push_ascii(axis);
        }
    }
    if l.len() == at {
        l.push_str("--");
    }
}

/// "12.3s" or "2m05s".
fn time_text(ms: u32) -> TextLine {
    let mut s = TextLine::new();
    let tenths = ms / 100;
    if tenths < 600 {
        s.push_number(Some((false, tenths)), 1, 0);
    } else {
        let secs = ms / 1000;
        s.push_uint(secs / 60, 0);
        s.push_str(if secs % 60 < 10 { "m0" } else { "m" });
        s.push_uint(secs % 60, 0);
    }
    s.push_ascii(b's');
    s
}

/// The screens' retained state.
#[derive(Clone, Debug)]
pub struct Screens {
    key: Option<PageKey>,
    plot: Option<Plot>,
    trace: Trace,
    trace_run: Option<u32>,
    ticks: Option<Px>,
    arrow: Option<([i8; 2], bool)>,
    /// What the last render drew from: the HMI's revision and the machine status
    /// (see [`Screens::render`]).
    drawn: Option<(u32, Snapshot)>,
}

impl Default for Screens {
    fn default() -> Self {
        Self::new()
    }
}

impl Screens {
    pub const fn new() -> Self {
        Screens {
            key: None,
            plot: None,
            trace: Trace::new(),
            trace_run: None,
            ticks: None,
            arrow: None,
            drawn: None,
        }
    }

    /// Rebuild the whole screen on the next render (e.g. after an LCD reset).
    pub fn invalidate(&mut self) {
        self.key = None;
    }

    /// The pen trace of the drawing page.
    pub fn trace(&self) -> &Trace {
        &self.trace
    }

    /// Draw the current page of `hmi` for machine status `st` (never fails: the result
    /// is kept for the callers written against a fallible drawing target).
    ///
    /// Quiet when nothing changed: painting a page's text cells pixel by pixel costs
    /// the firmware milliseconds of CPU even when no pixel changes (emu/README.md has
    /// the measured load), so a render from the same HMI revision ([`Hmi::revision`])
    /// and machine status as the last one is skipped; the frame buffer already holds
    /// exactly that picture. The drawing page is the exception (its clock runs with
    /// `now_ms`), and is always drawn. One `Screens` draws one HMI.
    pub fn render(
        &mut self,
        hmi: &Hmi,
        st: &Snapshot,
        now_ms: u32,
        fb: &mut FrameBuffer,
    ) -> Result<(), Infallible> {
        let now = (hmi.revision(), *st);
        let timed = matches!(hmi.page(), Page::Run(_));
        if self.key.is_some() && !timed && self.drawn == Some(now) {
            return Ok(());
        }
        self.draw(hmi, st, now_ms, fb);
        self.drawn = Some(now);
        Ok(())
    }

    fn draw(&mut self, hmi: &Hmi, st: &Snapshot, now_ms: u32, fb: &mut FrameBuffer) {
        let page = hmi.page();
        let key = match hmi.prompt() {
            // The prompt covers the page; M0's and each pen's are distinct pages.
            Some(p) => [10, p.pen.map_or(0, |n| u32::from(n) + 1), 0, 0, 0, 0],
            None => page_key(page),
        };
        let fresh = self.key != Some(key);
        // The HMI is as the last render drew it (only the status moved on): what
        // depends on the HMI alone is on the screen already.
        let hmi_drawn = !fresh && self.drawn.is_some_and(|(r, _)| r == hmi.revision());
        if fresh {
            fb.fill(0, 0, 128, 64, false);
            self.arrow = None;
            self.ticks = None;
            // A new run starts a new trace; a rebuilt page of the same run keeps it.
            let run = match page {
                Page::Run(r) => Some(r.started_ms),
                _ => None,
            };
            if run.is_none() || run != self.trace_run {
                self.trace.clear();
                self.trace_run = run;
            }
            self.key = Some(key);
        }
        let toast = hmi.toast().map(|t| t.bytes());
        let p = hmi.pos_mm(st);
        let pen_down = hmi.pen_is_down(st);
        let state = st.state.name().as_bytes();
        let mut l = TextLine::new();
        if let Some(prompt) = hmi.prompt() {
            prompt_page(fb, prompt, state, &mut l);
            return;
        }
        let hint: &[u8] = match page {
            Page::Boot => {
                if fresh {
                    boot(fb);
                }
                return;
            }
            Page::Menu { sel } | Page::Machine { sel } => {
                let main = matches!(page, Page::Menu { .. });
                let (title, lines): (&[u8], &[&str]) = if main {
                    (b"inkstep", &MENU_LINES)
                } else {
                    (b"Machine", &MACHINE_LINES)
                };
                let count = lines.len();
                title_bar(fb, title, state);
                // The rows and the scroll bar follow the selection only (the moving
                // machine repaints just the title's state and the bottom line).
                if !hmi_drawn {
                    let top = sel.saturating_sub(ROWS - 1).min(count.saturating_sub(ROWS));
                    for row in 0..ROWS {
                        let i = top + row;
                        let line = lines.get(i).map_or(&[][..], |s| s.as_bytes());
                        put(fb, Cell::at(0, row_y(row), 20).inverse(i == *sel), line);
                    }
                    if count > ROWS {
                        scroll_bar(fb, top, count);
                    }
                }
                // "X12.3 Y-4.5 pen up" for the menus' bottom line.
                let tpl: &[u8] = if pen_down {
                    b"X\x02 Y\x02 pen dn"
                } else {
                    b"X\x02 Y\x02 pen up"
                };
                fill(&mut l, tpl, &[p[X], p[Y]])
            }
            Page::Form(form) => {
                let fields = form.fields();
                // "2/4": the field and the count.
                l.clear();
                l.push_uint(form.cur as u32 + 1, 0);
                l.push_ascii(b'/');
                l.push_uint(fields.len() as u32, 0);
                title_bar(fb, form.kind.title().as_bytes(), l.bytes());
                for (i, f) in fields.iter().take(ROWS).enumerate() {
                    let (y, current) = (row_y(i), i == form.cur);
                    put(fb, Cell::at(0, y, 6), f.label().as_bytes());
                    l.clear();
                    f.push_display(&mut l);
                    l.push_str(if current && f.editing() { "_" } else { " " });
                    put(fb, Cell::at(36, y, 9).inverse(current).right(), l.bytes());
                    put(fb, Cell::at(93, y + 1, 7).small(), f.unit().as_bytes());
                }
                if fresh && fields.len() < ROWS {
                    put(fb, Cell::at(0, 44, 25).small(), form.kind.note().as_bytes());
                }
                b"D:ok C:del/esc A/B:field"
            }
            Page::Preview { job, .. } => {
                if fresh {
                    preview_page(hmi, job, fb);
                }
                b"D:draw      C:back"
            }
            Page::Run(run) => {
                self.run_page(hmi, st, now_ms, run, fresh, fb);
                return;
            }
            Page::Jog(jog) => {
                title_bar(fb, b"Jog", state);
                let shown = (
                    jog.active.map_or(jog.last_dir, |(_, dir)| dir),
                    jog.active.is_some(),
                );
                if self.arrow != Some(shown) {
                    fb.fill(4, 12, 40, 40, false);
                    arrow(fb, 4, 12, 40, shown.0, shown.1);
                    self.arrow = Some(shown);
                }
                // "X" + value right-aligned, e.g. "X  -12.34".
                put_line(fb, Cell::at(52, 12, 12), &mut l, b"X\x17", &[p[X]]);
                put_line(fb, Cell::at(52, 22, 12), &mut l, b"Y\x17", &[p[Y]]);
                let c = Cell::at(52, 32, 12);
                put_line(fb, c, &mut l, b"F \x0c mm/m", &[hmi.jog_speed()]);
                let pen: &[u8] = if pen_down { b"Pen down" } else { b"Pen up" };
                put(fb, Cell::at(52, 42, 12), pen);
                b"hold 1-9:move A/B:F 5:pen"
            }
            Page::Status => {
                title_bar(fb, b"Status / setup", state);
                let row = |i| Cell::at(0, row_y(i), 21);
                put_line(fb, row(0), &mut l, b"X \x03  Y \x03", &[p[X], p[Y]]);
                let tpl: &[u8] = if pen_down {
                    b"Z \x03  pen down"
                } else {
                    b"Z \x03  pen up"
                };
                put_line(fb, row(1), &mut l, tpl, &[p[2]]);
                let spmm = &hmi.config().steps_per_mm;
                put_line(fb, row(2), &mut l, b"step/mm \x01 \x01 \x01", spmm);
                let c = row(3).inverse(true);
                put_line(fb, c, &mut l, b"Draw F \x0c mm/min", &[hmi.draw_feed()]);
                fill(&mut l, b"A/B:draw F  jog F \x08", &[hmi.jog_speed()])
            }
            Page::Alarm { code } => {
                title_bar(fb, b"!! ALARM", fill(&mut l, b"#\x08", &[f32::from(*code)]));
                if fresh {
                    let text = alarm_text(*code);
                    let n = text.len().min(19);
                    let x = (128 - 6 * n as i32 - 12) / 2;
                    fb.fill(x, 17, 6 * n as i32 + 12, 16, true);
                    put(fb, Cell::at(x + 6, 20, n).inverse(true), text.as_bytes());
                }
                put_line(
                    fb,
                    Cell::at(0, 41, 21),
                    &mut l,
                    b"at X\x03 Y\x03",
                    &[p[X], p[Y]],
                );
                b"D:unlock      C:menu"
            }
            Page::Error { title, text } => {
                title_bar(fb, title.as_bytes(), b"!");
                if fresh {
                    put(fb, Cell::at(0, 21, 21), text.as_bytes());
                }
                bottom_line(fb, b"any key: back to menu", None);
                return;
            }
        };
        bottom_line(fb, hint, toast);
    }

    fn run_page(
        &mut self,
        hmi: &Hmi,
        st: &Snapshot,
        now_ms: u32,
        run: &crate::hmi::RunPage,
        fresh: bool,
        fb: &mut FrameBuffer,
    ) {
        title_bar(
            fb,
            run.job.name().as_bytes(),
            time_text(run.elapsed_ms(now_ms)).bytes(),
        );
        let plot = match (fresh, self.plot) {
            (false, Some(p)) => p,
            _ => {
                let p = Plot::fit(&run.job, RUN_BOX);
                self.plot = Some(p);
                p
            }
        };
        if fresh {
            let [x, y, w, h] = RUN_BOX;
            widgets::frame(fb, x, y, w, h, true);
            plot.draw_preview(&run.job, fb);
            self.trace.draw(fb);
        }
        // The pen: extend the trace while the pen is down, move the edge ticks.
        let spmm = hmi.config().steps_per_mm;
        let rel = [
            (st.pos[X].wrapping_sub(run.start[X])) as f32 / spmm[X],
            (st.pos[Y].wrapping_sub(run.start[Y])) as f32 / spmm[Y],
        ];
        let px = plot.to_px(rel);
        if run.job.draws() && hmi.pen_is_down(st) {
            if let Some((a, b)) = self.trace.push(px) {
                widgets::line(fb, a, b);
            }
        }
        if self.ticks != Some(px) {
            let bottom = RUN_BOX[1] + RUN_BOX[3];
            if let Some(old) = self.ticks {
                fb.fill(old.0 - 1, bottom, 3, 2, false);
                fb.fill(0, old.1 - 1, 2, 3, false);
            }
            fb.fill(px.0 - 1, bottom, 3, 2, true);
            fb.fill(0, px.1 - 1, 2, 3, true);
            self.ticks = Some(px);
        }
        // Live values.
        let p = hmi.pos_mm(st);
        let mut l = TextLine::new();
        put_line(fb, Cell::at(76, 11, 8), &mut l, b"X\x17", &[p[X]]);
        put_line(fb, Cell::at(76, 21, 8), &mut l, b"Y\x17", &[p[Y]]);
        // (`as u32` saturates: a negative or NaN feed shows 0.)
        let feed = [st.feed_mm_min];
        put_line(
            fb,
            Cell::at(76, 31, 10).small(),
            &mut l,
            b"F \x0cmm/m",
            &feed,
        );
        // Teaching view: the feed direction now and the ones before it.
        l.clear();
        l.push_str("feed ");
        push_dir(&mut l, st.dir);
        put(fb, Cell::at(76, 39, 10).small(), l.bytes());
        l.clear();
        let previous = hmi.feed_dirs().rev().skip(usize::from(st.dir != [0, 0]));
        l.push_str("was");
        for dir in previous {
            let at = l.len();
            l.push_str(" ");
            push_dir(&mut l, *dir);
            if l.len() > 10 {
                l.truncate(at);
                break;
            }
        }
        put(fb, Cell::at(76, 47, 10).small(), l.bytes());
        // Progress and state.
        let frac = run.progress();
        progress(fb, 0, 56, 62, 8, frac);
        let state = match run.phase {
            RunPhase::Running if st.state == MachineState::Hold => "HOLD",
            RunPhase::Running => "RUN",
            RunPhase::Stopping => "STOP",
            RunPhase::Done { complete: true, .. } => "DONE",
            RunPhase::Done { .. } => "SHORT",
        };
        fill(&mut l, b"\x0b% ", &[fmath::round(frac * 100.0)]);
        l.push_str(state);
        put(fb, Cell::at(65, 56, 12).small(), l.bytes());
    }
}

fn preview_page(hmi: &Hmi, job: &Job, fb: &mut FrameBuffer) {
    let mut t = TextLine::new();
    t.push_str(job.name());
    t.push_str(": preview");
    title_bar(fb, t.bytes(), b"");
    let [x, y, w, h] = PREVIEW_BOX;
    widgets::frame(fb, x, y, w, h, true);
    let plot = Plot::fit(job, PREVIEW_BOX);
    plot.draw_preview(job, fb);
    // The start point: a small filled square.
    let s = plot.to_px([0.0, 0.0]);
    fb.fill(s.0 - 1, s.1 - 1, 3, 3, true);
    let (lo, hi, len) = job.sweep();
    let feed = hmi.draw_feed().max(1.0);
    let rows: [(&[u8], f32); 4] = [
        (b"W \x02", hi[0] - lo[0]),
        (b"H \x02", hi[1] - lo[1]),
        (b"L \x02", len),
        (b"t \x01s", len / feed * 60.0),
    ];
    for (i, &(tpl, v)) in rows.iter().enumerate() {
        put_line(fb, Cell::at(83, row_y(i), 7), &mut t, tpl, &[v]);
    }
}

/// The list's scroll bar in x 123..=125, rows 11..=50, painted pixel-exact.
fn scroll_bar(fb: &mut FrameBuffer, top: usize, count: usize) {
    let track = 40i32;
    let len = (track * ROWS as i32 / count as i32).max(4);
    let pos = (track - len) * top as i32 / (count - ROWS) as i32;
    let x = 123;
    let rest = (track - pos - len).max(0);
    // Outside the thumb: a 1-pixel track line in the middle column.
    for (y0, h) in [(11, pos), (11 + pos + len, rest)] {
        fb.fill(x, y0, 1, h, false);
        fb.fill(x + 1, y0, 1, h, true);
        fb.fill(x + 2, y0, 1, h, false);
    }
    fb.fill(x, 11 + pos, 3, len, true);
}

/// The boot screen's sine period: row of x = 16 + 2i, i.e. round(32 - 7 sin(2 pi i / 48))
/// (checked against the formula in the tests).
const BOOT_WAVE: [u8; 49] = [
    32, 31, 30, 29, 29, 28, 27, 26, 26, 26, 25, 25, 25, 25, 25, 26, 26, 26, 27, 28, 29, 29, 30, 31,
    32, 33, 34, 35, 36, 36, 37, 38, 38, 38, 39, 39, 39, 39, 39, 38, 38, 38, 37, 36, 36, 35, 34, 33,
    32,
];

fn boot(fb: &mut FrameBuffer) {
    // The name in an inverted banner, one period of the report's signature curve under it.
    fb.fill(34, 4, 60, 16, true);
    put(fb, Cell::at(43, 7, 7).inverse(true), b"inkstep");
    let mut prev: Option<Px> = None;
    for (i, &y) in BOOT_WAVE.iter().enumerate() {
        let p = (16 + 2 * i as i32, i32::from(y));
        widgets::line(fb, prev.unwrap_or(p), p);
        prev = Some(p);
    }
    put(fb, Cell::at(31, 42, 11), b"pen plotter");
    put(fb, Cell::at(9, 55, 22).small(), b"STM32F103 + ST7920 LCD");
}

/// The machine waits for the user: M0's pause or M6's pen change, with the last
/// `(MSG, ...)` text on two lines, and what D does.
fn prompt_page(
    fb: &mut FrameBuffer,
    prompt: &crate::hmi::PromptView,
    state: &[u8],
    l: &mut TextLine,
) {
    fb.fill(0, 11, 128, 43, false);
    let row = |i| Cell::at(0, row_y(i), 21);
    match prompt.pen {
        None => {
            title_bar(fb, b"Paused", state);
            put(fb, row(0), b"Paused: press D to");
            put(fb, row(1), b"continue");
        }
        Some(n) => {
            title_bar(fb, b"Pen change", state);
            put_line(fb, row(0).inverse(true), l, b"Pen \x08", &[f32::from(n)]);
            put(fb, row(1), b"Put it in, press D");
        }
    }
    let msg = prompt.message.bytes();
    let (first, rest) = msg.split_at(msg.len().min(21));
    put(fb, row(2), first);
    put(fb, row(3), rest.strip_prefix(b" ").unwrap_or(rest));
    bottom_line(fb, b"D:continue", None);
}

#[cfg(test)]
mod tests {
    use super::framebuffer::FrameBuffer;
    use super::*;
    use crate::hmi::{Config, MachineState};
    use crate::keypad::{Key, KeyEvent, KeyKind};

    fn press(hmi: &mut Hmi, st: &Snapshot, key: Key, now: u32) {
        hmi.key(
            KeyEvent {
                key,
                kind: KeyKind::Press,
            },
            st,
            now,
        );
        hmi.key(
            KeyEvent {
                key,
                kind: KeyKind::Release,
            },
            st,
            now,
        );
    }

    #[test]
    fn boot_wave_is_one_sine_period() {
        for (i, &y) in BOOT_WAVE.iter().enumerate() {
            let want = 32.0 - 7.0 * libm::sinf(i as f32 / 48.0 * 2.0 * core::f32::consts::PI);
            assert_eq!(f32::from(y), libm::roundf(want), "i = {i}");
        }
    }

    #[test]
    fn row_y_is_the_row_table() {
        for (i, y) in [11, 21, 31, 41].iter().enumerate() {
            assert_eq!(row_y(i), *y);
        }
    }

    #[test]
    fn text_helpers() {
        let dir_text = |d| {
            let mut l = TextLine::new();
            push_dir(&mut l, d);
            l
        };
        assert_eq!(dir_text([1, -1]).as_str(), "+X-Y");
        assert_eq!(dir_text([0, 1]).as_str(), "+Y");
        assert_eq!(dir_text([0, 0]).as_str(), "--");
        assert_eq!(time_text(12_345).as_str(), "12.3s");
        assert_eq!(time_text(125_000).as_str(), "2m05s");
        let mut l = TextLine::new();
        assert_eq!(fill(&mut l, b"X\x17", &[-12.345]), b"X -12.35");
        assert_eq!(fill(&mut l, b"F \x0c mm/m", &[600.9]), b"F  600 mm/m");
        assert_eq!(fill(&mut l, b"X\x02 Y\x01s", &[1.0, -2.5]), b"X1.0 Y-3s");
    }

    /// While drawing, a refresh sends only the changed cells and the new trace: far
    /// below the 10 Hz budget.
    #[test]
    fn drawing_refresh_is_a_small_fraction_of_a_full_frame() {
        let cfg = Config::default();
        let mut hmi = Hmi::new(cfg, 0);
        let mut st = Snapshot::idle_at([0, 0, 500]);
        hmi.tick(&st, 2000);
        press(&mut hmi, &st, Key::Digit(5), 2100); // sine
        for _ in 0..4 {
            press(&mut hmi, &st, Key::Enter, 2200);
        }
        press(&mut hmi, &st, Key::Enter, 2300);
        assert!(matches!(hmi.page(), Page::Run(_)));
        let mut fb = FrameBuffer::new();
        let mut screens = Screens::new();
        screens.render(&hmi, &st, 2300, &mut fb).unwrap();
        fb.mark_clean();
        st.state = MachineState::Run;
        st.queue_empty = false;
        let mut worst = 0;
        let job = Job::Sine {
            amp: 10.0,
            omega: 0.2,
            phase: 0.0,
            len: 60.0,
        };
        for i in 1..=60u32 {
            let t = i as f32 / 60.0;
            let p = job.point_at(t);
            st.pos = [(p[0] * 80.0) as i32, (p[1] * 80.0) as i32, 0];
            st.feed_mm_min = 600.0;
            st.dir = [1, if i % 10 < 5 { 1 } else { -1 }];
            let now = 2300 + i * 100;
            hmi.tick(&st, now);
            screens.render(&hmi, &st, now, &mut fb).unwrap();
            worst = worst.max(st7920::pending_bytes(&fb));
            fb.mark_clean();
        }
        assert!(screens.trace().len() > 20);
        // Measured: well under a third of the full frame; 100 ms holds at 10 Hz.
        assert!(worst < st7920::FULL_FRAME_BYTES / 3, "worst {worst} bytes");
        assert!(st7920::transfer_us(worst) < 40_000);
    }

    #[test]
    fn an_unchanged_page_repaints_nothing() {
        let mut hmi = Hmi::new(Config::default(), 0);
        let st = Snapshot::idle_at([0, 0, 500]);
        hmi.tick(&st, 2000);
        let mut fb = FrameBuffer::new();
        let mut screens = Screens::new();
        for key in [
            None,
            Some(Key::Digit(1)),
            Some(Key::Back),
            Some(Key::Digit(0)),
        ] {
            if let Some(k) = key {
                press(&mut hmi, &st, k, 2100);
            }
            screens.render(&hmi, &st, 2100, &mut fb).unwrap();
            fb.mark_clean();
            screens.render(&hmi, &st, 2200, &mut fb).unwrap();
            assert!(!fb.is_dirty(), "page {:?} repainted", hmi.page());
        }
    }

    /// A render from an unchanged state is skipped, and the picture is the one a full
    /// render of that state gives; a changed status is drawn.
    #[test]
    fn an_unchanged_state_is_not_drawn_again() {
        let mut hmi = Hmi::new(Config::default(), 0);
        let mut st = Snapshot::idle_at([0, 0, 500]);
        hmi.tick(&st, 2000);
        let mut fb = FrameBuffer::new();
        let mut screens = Screens::new();
        screens.render(&hmi, &st, 2000, &mut fb).unwrap();
        fb.mark_clean();
        // Scribble on the buffer: a skipped render leaves it alone.
        let mut scribbled = fb.clone();
        scribbled.set(0, 0, !fb.pixel(0, 0));
        scribbled.mark_clean();
        screens.render(&hmi, &st, 2100, &mut scribbled).unwrap();
        assert!(!scribbled.is_dirty(), "the unchanged menu was drawn again");
        let mut fresh = FrameBuffer::new();
        Screens::new().render(&hmi, &st, 2100, &mut fresh).unwrap();
        assert!(fresh.bytes() == fb.bytes());
        // The position on the menu's bottom line changed: drawn.
        st.pos[X] = 800;
        screens.render(&hmi, &st, 2200, &mut fb).unwrap();
        assert!(fb.is_dirty());
        let mut fresh = FrameBuffer::new();
        Screens::new().render(&hmi, &st, 2200, &mut fresh).unwrap();
        assert!(fresh.bytes() == fb.bytes());
    }

    /// Whatever the keys, the time and the machine do, the picture after a render (drawn
    /// or skipped) is exactly what a full render of the same state draws: every change
    /// the screens show bumps the HMI's revision or is in the status.
    #[test]
    fn skipped_renders_never_leave_a_stale_picture() {
        use proptest::prelude::*;
        let keys = [
            Key::Digit(1),
            Key::Digit(2),
            Key::Digit(5),
            Key::Digit(8),
            Key::Up,
            Key::Down,
            Key::Back,
            Key::Enter,
            Key::Dot,
            Key::Sign,
        ];
        // (what happens: 0-9 a key, 10 an alarm, 11 idle again, 12 a move, else time
        // passes; how long it takes in ms)
        let steps = proptest::collection::vec((0u8..16, 0u32..1500), 1..60);
        proptest!(ProptestConfig::with_cases(200), |(steps in steps)| {
            let mut hmi = Hmi::new(Config::default(), 0);
            let mut st = Snapshot::idle_at([0, 0, 500]);
            let mut screens = Screens::new();
            let mut fb = FrameBuffer::new();
            let mut now = 0u32;
            for (what, dt) in steps {
                now += dt;
                match what {
                    0..=9 => press(&mut hmi, &st, keys[usize::from(what)], now),
                    10 => st.state = MachineState::Alarm(1),
                    11 => st.state = MachineState::Idle,
                    12 => st.pos[X] += 80,
                    _ => {}
                }
                hmi.tick(&st, now);
                screens.render(&hmi, &st, now, &mut fb).unwrap();
                let mut fresh = FrameBuffer::new();
                Screens::new().render(&hmi, &st, now, &mut fresh).unwrap();
                prop_assert!(fresh.bytes() == fb.bytes(), "stale picture on {:?}", hmi.page());
            }
        });
    }

    /// Rebuilding the drawing page (after an LCD reset) restores exactly what the
    /// incremental refreshes painted, trace included.
    #[test]
    fn rebuilt_drawing_page_matches_the_incremental_one() {
        let mut hmi = Hmi::new(Config::default(), 0);
        let mut st = Snapshot::idle_at([0, 0, 500]);
        hmi.tick(&st, 2000);
        press(&mut hmi, &st, Key::Digit(6), 2100); // star
        press(&mut hmi, &st, Key::Enter, 2200);
        press(&mut hmi, &st, Key::Enter, 2300);
        let mut fb = FrameBuffer::new();
        let mut screens = Screens::new();
        st.state = MachineState::Run;
        st.queue_empty = false;
        let Page::Run(run) = *hmi.page() else {
            panic!("not drawing")
        };
        for i in 0..=40u32 {
            let p = run.job.point_at(i as f32 / 50.0);
            st.pos = [(p[0] * 80.0) as i32, (p[1] * 80.0) as i32, 0];
            st.dir = [1, -1];
            hmi.tick(&st, 2400 + i * 100);
            screens.render(&hmi, &st, 2400 + i * 100, &mut fb).unwrap();
        }
        assert!(screens.trace().len() > 10);
        let mut rebuilt = screens.clone();
        rebuilt.invalidate();
        let mut fresh = FrameBuffer::new();
        rebuilt.render(&hmi, &st, 6400, &mut fresh).unwrap();
        assert!(fresh.bytes() == fb.bytes());
    }
}
