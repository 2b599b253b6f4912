//! The LCD pages: what each [`Page`] of the HMI looks like on the 128x64 ST7920, drawn
//! with embedded-graphics onto any `DrawTarget<Color = BinaryColor>`.
//!
//! [`Screens`] is retained-mode on purpose: when the page changes it clears and draws
//! the static parts (frames, labels, the curve preview) once; on every later refresh it
//! repaints only the live cells (coordinates, speed, progress, the trace's new segment,
//! the pen ticks) in place. With the dirty-tracking [`framebuffer::FrameBuffer`] that
//! means a refresh while drawing sends a few hundred bytes, not the whole screen (see
//! [`st7920`] for the SPI budget). The small state it keeps (page identity, the preview
//! fit, the pen trace, the last arrow and ticks) is what the retained drawing needs.
//!
//! Fonts are chosen in [`fonts`]; shared pieces are in [`widgets`].

pub mod fonts;
pub mod framebuffer;
pub mod plot;
pub mod st7920;
pub mod widgets;

use crate::fmath;
use embedded_graphics::pixelcolor::BinaryColor;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::Rectangle;
use heapless::String;

use crate::hmi::entry::FormKind;
use crate::hmi::fixed::{push_fixed, push_uint};
use crate::hmi::job::Job;
use crate::hmi::{alarm_text, Hmi, Page, RunPhase, Status, MACHINE_MENU, MENU};
use crate::motion::{X, Y};
use plot::{Plot, Trace};
use widgets::{arrow, bottom_line, progress, put, title_bar, Cell};

const ON: BinaryColor = BinaryColor::On;
const OFF: BinaryColor = BinaryColor::Off;

/// Rows of a list or form page (below the title, above the bottom line).
const ROW_Y: [i32; 4] = [11, 21, 31, 41];

/// `ROW_Y[i]` by arithmetic (cheaper than iterating the array by value).
const fn row_y(i: usize) -> i32 {
    11 + 10 * i as i32
}
/// The preview / trace box of the drawing page.
const RUN_BOX: Rectangle = Rectangle::new(Point::new(2, 11), Size::new(72, 42));
/// The preview box of the "ready to draw" page.
const PREVIEW_BOX: Rectangle = Rectangle::new(Point::new(0, 11), Size::new(80, 43));
/// The jog direction arrow.
const ARROW_BOX: Rectangle = Rectangle::new(Point::new(4, 12), Size::new(40, 40));

/// Which page (and which instance of it) is on the screen.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PageKey {
    Boot,
    Menu,
    Machine,
    Jog,
    Form(FormKind),
    Preview(Job),
    Run(u32),
    Status,
    Alarm(u8),
    Error,
}

fn page_key(page: &Page) -> PageKey {
    match page {
        Page::Boot => PageKey::Boot,
        Page::Menu { .. } => PageKey::Menu,
        Page::Machine { .. } => PageKey::Machine,
        Page::Jog(_) => PageKey::Jog,
        Page::Form(f) => PageKey::Form(f.kind),
        Page::Preview { job, .. } => PageKey::Preview(*job),
        Page::Run(r) => PageKey::Run(r.started_ms),
        Page::Status => PageKey::Status,
        Page::Alarm { code } => PageKey::Alarm(*code),
        Page::Error { .. } => PageKey::Error,
    }
}

type Line = String<32>;

/// "+X-Y" for a direction; "--" for none.
fn dir_text(dir: [i8; 2]) -> String<6> {
    let mut s = String::new();
    for &(v, axis) in [(dir[0], 'X'), (dir[1], 'Y')].iter() {
        if v != 0 {
            let _ = s.push(if v > 0 { '+' } else { '-' });
            let _ = s.push(axis);
        }
    }
    if s.is_empty() {
        let _ = s.push_str("--");
    }
    s
}

/// "12.3s" or "2m05s".
fn time_text(ms: u32) -> String<10> {
    let mut s = String::new();
    let tenths = ms / 100;
    if tenths < 600 {
        push_uint(&mut s, tenths / 10, 0);
        let _ = s.push('.');
        push_uint(&mut s, tenths % 10, 0);
        let _ = s.push('s');
    } else {
        let secs = ms / 1000;
        push_uint(&mut s, secs / 60, 0);
        let _ = s.push('m');
        if secs % 60 < 10 {
            let _ = s.push('0');
        }
        push_uint(&mut s, secs % 60, 0);
        let _ = s.push('s');
    }
    s
}

/// "X" + value right-aligned, e.g. "X  -12.34".
fn axis_text(axis: char, mm: f32) -> Line {
    let mut v: Line = String::new();
    push_fixed(&mut v, mm, 2);
    let mut s: Line = String::new();
    let _ = s.push(axis);
    for _ in v.len()..7 {
        let _ = s.push(' ');
    }
    let _ = s.push_str(&v);
    s
}

/// The screens' retained state.
#[derive(Clone, Debug, Default)]
pub struct Screens {
    key: Option<PageKey>,
    plot: Option<Plot>,
    trace: Trace,
    trace_run: Option<u32>,
    ticks: Option<Point>,
    arrow: Option<([i8; 2], bool)>,
}

impl Screens {
    pub fn new() -> Self {
        Self::default()
    }

    /// Rebuild the whole screen on the next render (e.g. after an LCD reset).
    pub fn invalidate(&mut self) {
        self.key = None;
    }

    /// The pen trace of the drawing page.
    pub fn trace(&self) -> &Trace {
        &self.trace
    }

    /// Draw the current page of `hmi` for machine status `st`.
    pub fn render<D>(
        &mut self,
        hmi: &Hmi,
        st: &Status,
        now_ms: u32,
        d: &mut D,
    ) -> Result<(), D::Error>
    where
        D: DrawTarget<Color = BinaryColor>,
    {
        let page = hmi.page();
        let key = page_key(page);
        let fresh = self.key != Some(key);
        if fresh {
            d.clear(OFF)?;
            self.arrow = None;
            self.ticks = None;
            // A new run starts a new trace; a rebuilt page of the same run keeps it.
            let run = match key {
                PageKey::Run(t) => Some(t),
                _ => None,
            };
            if run.is_none() || run != self.trace_run {
                self.trace.clear();
                self.trace_run = run;
            }
            self.key = Some(key);
        }
        match page {
            Page::Boot => {
                if fresh {
                    boot(d)?;
                }
                Ok(())
            }
            Page::Menu { sel } | Page::Machine { sel } => {
                let main = matches!(page, Page::Menu { .. });
                let item = |i: usize| {
                    if main {
                        MENU.get(i).map(|(k, m)| (*k, m.label()))
                    } else {
                        MACHINE_MENU.get(i).map(|(k, m)| (*k, m.label()))
                    }
                };
                let (title, count) = if main {
                    ("inkstep", MENU.len())
                } else {
                    ("Machine", MACHINE_MENU.len())
                };
                list(d, title, st.state.name(), &item, count, *sel)?;
                bottom_line(d, &position_hint(hmi, st), hmi.toast())
            }
            Page::Form(form) => {
                let mut right: String<6> = String::new();
                push_uint(&mut right, form.cur as u32 + 1, 0);
                let _ = right.push('/');
                push_uint(&mut right, form.fields().len() as u32, 0);
                title_bar(d, form.kind.title(), &right)?;
                for (i, f) in form.fields().iter().take(ROW_Y.len()).enumerate() {
                    let (y, current) = (row_y(i), i == form.cur);
                    put(d, Cell::at(0, y, 6), f.label)?;
                    let mut v: String<14> = String::new();
                    let _ = v.push_str(&f.display());
                    let _ = v.push(if current && f.editing() { '_' } else { ' ' });
                    put(d, Cell::at(36, y, 9).inverse(current).right(), &v)?;
                    put(d, Cell::at(93, y + 1, 7).small(), f.unit)?;
                }
                if fresh && form.fields().len() < ROW_Y.len() {
                    put(d, Cell::at(0, 44, 25).small(), form.kind.note())?;
                }
                bottom_line(d, "D:ok C:del/esc A/B:field", hmi.toast())
            }
            Page::Preview { job, .. } => {
                if fresh {
                    self.preview_page(hmi, job, d)?;
                }
                bottom_line(d, "D:draw      C:back", hmi.toast())
            }
            Page::Run(run) => self.run_page(hmi, st, now_ms, run, fresh, d),
            Page::Jog(jog) => {
                title_bar(d, "Jog", st.state.name())?;
                let shown = (
                    jog.active.map_or(jog.last_dir, |(_, dir)| dir),
                    jog.active.is_some(),
                );
                if self.arrow != Some(shown) {
                    d.fill_solid(&ARROW_BOX, OFF)?;
                    arrow(d, ARROW_BOX, shown.0, shown.1)?;
                    self.arrow = Some(shown);
                }
                let p = hmi.pos_mm(st);
                put(d, Cell::at(52, 12, 12), &axis_text('X', p[X]))?;
                put(d, Cell::at(52, 22, 12), &axis_text('Y', p[Y]))?;
                let mut f: Line = String::new();
                let _ = f.push_str("F ");
                push_uint(&mut f, hmi.jog_speed() as u32, 4);
                let _ = f.push_str(" mm/m");
                put(d, Cell::at(52, 32, 12), &f)?;
                let pen = if hmi.pen_is_down(st) {
                    "Pen down"
                } else {
                    "Pen up"
                };
                put(d, Cell::at(52, 42, 12), pen)?;
                bottom_line(d, "hold 1-9:move A/B:F 5:pen", hmi.toast())
            }
            Page::Status => {
                title_bar(d, "Status / setup", st.state.name())?;
                let p = hmi.pos_mm(st);
                let cfg = hmi.config();
                let mut l: Line = String::new();
                let _ = l.push_str("X ");
                push_fixed(&mut l, p[X], 2);
                let _ = l.push_str("  Y ");
                push_fixed(&mut l, p[Y], 2);
                put(d, Cell::at(0, ROW_Y[0], 21), &l)?;
                l.clear();
                let _ = l.push_str("Z ");
                push_fixed(&mut l, p[2], 2);
                let _ = l.push_str(if hmi.pen_is_down(st) {
                    "  pen down"
                } else {
                    "  pen up"
                });
                put(d, Cell::at(0, ROW_Y[1], 21), &l)?;
                l.clear();
                let _ = l.push_str("step/mm");
                for s in cfg.steps_per_mm {
                    let _ = l.push(' ');
                    push_fixed(&mut l, s, 0);
                }
                put(d, Cell::at(0, ROW_Y[2], 21), &l)?;
                l.clear();
                let _ = l.push_str("Draw F ");
                push_uint(&mut l, hmi.draw_feed() as u32, 4);
                let _ = l.push_str(" mm/min");
                put(d, Cell::at(0, ROW_Y[3], 21).inverse(true), &l)?;
                let mut h: Line = String::new();
                let _ = h.push_str("A/B:draw F  jog F ");
                push_uint(&mut h, hmi.jog_speed() as u32, 0);
                bottom_line(d, &h, hmi.toast())
            }
            Page::Alarm { code } => {
                let mut right: String<6> = String::new();
                let _ = right.push('#');
                push_uint(&mut right, u32::from(*code), 0);
                title_bar(d, "!! ALARM", &right)?;
                if fresh {
                    let text = alarm_text(*code);
                    let n = text.len().min(19);
                    let x = (128 - 6 * n as i32 - 12) / 2;
                    let banner =
                        Rectangle::new(Point::new(x, 17), Size::new(6 * n as u32 + 12, 16));
                    d.fill_solid(&banner, ON)?;
                    put(d, Cell::at(x + 6, 20, n).inverse(true), text)?;
                }
                let p = hmi.pos_mm(st);
                let mut l: Line = String::new();
                let _ = l.push_str("at X");
                push_fixed(&mut l, p[X], 2);
                let _ = l.push_str(" Y");
                push_fixed(&mut l, p[Y], 2);
                put(d, Cell::at(0, 41, 21), &l)?;
                bottom_line(d, "D:unlock      C:menu", hmi.toast())
            }
            Page::Error { title, text } => {
                title_bar(d, title, "!")?;
                if fresh {
                    put(d, Cell::at(0, 21, 21), text)?;
                }
                bottom_line(d, "any key: back to menu", None)
            }
        }
    }

    fn preview_page<D>(&mut self, hmi: &Hmi, job: &Job, d: &mut D) -> Result<(), D::Error>
    where
        D: DrawTarget<Color = BinaryColor>,
    {
        let mut t: Line = String::new();
        let _ = t.push_str(job.name());
        let _ = t.push_str(": preview");
        title_bar(d, &t, "")?;
        widgets::frame(d, PREVIEW_BOX, ON)?;
        let plot = Plot::fit(job, PREVIEW_BOX);
        plot.draw_preview(job, d)?;
        // The start point: a small filled square.
        let s = plot.to_px([0.0, 0.0]);
        d.fill_solid(&Rectangle::new(s - Point::new(1, 1), Size::new(3, 3)), ON)?;
        let (lo, hi, len) = job.sweep();
        let feed = hmi.draw_feed().max(1.0);
        let rows: [(&str, f32, u8, &str); 4] = [
            ("W ", hi[0] - lo[0], 1, ""),
            ("H ", hi[1] - lo[1], 1, ""),
            ("L ", len, 1, ""),
            ("t ", len / feed * 60.0, 0, "s"),
        ];
        for (i, (name, v, dec, unit)) in rows.iter().enumerate() {
            let y = row_y(i);
            let mut l: String<12> = String::new();
            let _ = l.push_str(name);
            push_fixed(&mut l, *v, *dec);
            let _ = l.push_str(unit);
            put(d, Cell::at(83, y, 7), &l)?;
        }
        Ok(())
    }

    fn run_page<D>(
        &mut self,
        hmi: &Hmi,
        st: &Status,
        now_ms: u32,
        run: &crate::hmi::RunPage,
        fresh: bool,
        d: &mut D,
    ) -> Result<(), D::Error>
    where
        D: DrawTarget<Color = BinaryColor>,
    {
        title_bar(d, run.job.name(), &time_text(run.elapsed_ms(now_ms)))?;
        let plot = match (fresh, self.plot) {
            (false, Some(p)) => p,
            _ => {
                let p = Plot::fit(&run.job, RUN_BOX);
                self.plot = Some(p);
                p
            }
        };
        if fresh {
            widgets::frame(d, RUN_BOX, ON)?;
            plot.draw_preview(&run.job, d)?;
            self.trace.draw(d)?;
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
                widgets::line(d, a, b)?;
            }
        }
        if self.ticks != Some(px) {
            let bottom = RUN_BOX.top_left.y + RUN_BOX.size.height as i32;
            if let Some(old) = self.ticks {
                d.fill_solid(
                    &Rectangle::new(Point::new(old.x - 1, bottom), Size::new(3, 2)),
                    OFF,
                )?;
                d.fill_solid(
                    &Rectangle::new(Point::new(0, old.y - 1), Size::new(2, 3)),
                    OFF,
                )?;
            }
            d.fill_solid(
                &Rectangle::new(Point::new(px.x - 1, bottom), Size::new(3, 2)),
                ON,
            )?;
            d.fill_solid(
                &Rectangle::new(Point::new(0, px.y - 1), Size::new(2, 3)),
                ON,
            )?;
            self.ticks = Some(px);
        }
        // Live values.
        let p = hmi.pos_mm(st);
        put(d, Cell::at(76, 11, 8), &axis_text('X', p[X]))?;
        put(d, Cell::at(76, 21, 8), &axis_text('Y', p[Y]))?;
        let mut l: Line = String::new();
        let _ = l.push_str("F ");
        push_uint(&mut l, st.feed_mm_min.max(0.0) as u32, 4);
        let _ = l.push_str("mm/m");
        put(d, Cell::at(76, 31, 10).small(), &l)?;
        // Teaching view: the feed direction now and the ones before it.
        l.clear();
        let _ = l.push_str("feed ");
        let _ = l.push_str(&dir_text(st.dir));
        put(d, Cell::at(76, 39, 10).small(), &l)?;
        l.clear();
        let previous = hmi.feed_dirs().rev().skip(usize::from(st.dir != [0, 0]));
        let _ = l.push_str("was");
        for dir in previous {
            let t = dir_text(*dir);
            if l.len() + 1 + t.len() > 10 {
                break;
            }
            let _ = l.push(' ');
            let _ = l.push_str(&t);
        }
        put(d, Cell::at(76, 47, 10).small(), &l)?;
        // Progress and state.
        progress(
            d,
            Rectangle::new(Point::new(0, 56), Size::new(62, 8)),
            run.progress(),
        )?;
        l.clear();
        let state = match run.phase {
            RunPhase::Running if st.state == crate::hmi::MachineState::Hold => "HOLD",
            RunPhase::Running => "RUN",
            RunPhase::Stopping => "STOP",
            RunPhase::Done { complete: true, .. } => "DONE",
            RunPhase::Done { .. } => "SHORT",
        };
        push_uint(&mut l, fmath::round(run.progress() * 100.0) as u32, 3);
        let _ = l.push_str("% ");
        let _ = l.push_str(state);
        put(d, Cell::at(65, 56, 12).small(), &l)
    }
}

/// "X12.3 Y-4.5 pen up" for the menus' bottom line.
fn position_hint(hmi: &Hmi, st: &Status) -> Line {
    let p = hmi.pos_mm(st);
    let mut l: Line = String::new();
    let _ = l.push('X');
    push_fixed(&mut l, p[X], 1);
    let _ = l.push_str(" Y");
    push_fixed(&mut l, p[Y], 1);
    let _ = l.push_str(if hmi.pen_is_down(st) {
        " pen dn"
    } else {
        " pen up"
    });
    l
}

/// A scrolling list of (hotkey, label) with the selected row inverted.
fn list<D>(
    d: &mut D,
    title: &str,
    right: &str,
    item: &dyn Fn(usize) -> Option<(u8, &'static str)>,
    count: usize,
    sel: usize,
) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    title_bar(d, title, right)?;
    let rows = ROW_Y.len();
    let top = sel.saturating_sub(rows - 1).min(count.saturating_sub(rows));
    for row in 0..rows {
        let y = row_y(row);
        let i = top + row;
        let mut l: Line = String::new();
        if let Some((hotkey, label)) = item(i) {
            let _ = l.push(' ');
            push_uint(&mut l, u32::from(hotkey), 0);
            let _ = l.push(' ');
            let _ = l.push_str(label);
        }
        put(d, Cell::at(0, y, 20).inverse(i == sel), &l)?;
    }
    // Scroll bar in x 123..=125, rows 11..=50, painted pixel-exact.
    if count > rows {
        let track = 40i32;
        let len = (track * rows as i32 / count as i32).max(4);
        let pos = (track - len) * top as i32 / (count - rows) as i32;
        let x = 123;
        let rest = (track - pos - len).max(0);
        // Outside the thumb: a 1-pixel track line in the middle column.
        for &(y0, h) in [(11, pos), (11 + pos + len, rest)].iter() {
            d.fill_solid(
                &Rectangle::new(Point::new(x, y0), Size::new(1, h as u32)),
                OFF,
            )?;
            d.fill_solid(
                &Rectangle::new(Point::new(x + 1, y0), Size::new(1, h as u32)),
                ON,
            )?;
            d.fill_solid(
                &Rectangle::new(Point::new(x + 2, y0), Size::new(1, h as u32)),
                OFF,
            )?;
        }
        d.fill_solid(
            &Rectangle::new(Point::new(x, 11 + pos), Size::new(3, len as u32)),
            ON,
        )?;
    }
    Ok(())
}

/// The boot screen's sine period: row of x = 16 + 2i, i.e. round(32 - 7 sin(2 pi i / 48))
/// (checked against the formula in the tests; a table costs 49 bytes, sinf far more).
const BOOT_WAVE: [u8; 49] = [
    32, 31, 30, 29, 29, 28, 27, 26, 26, 26, 25, 25, 25, 25, 25, 26, 26, 26, 27, 28, 29, 29, 30, 31,
    32, 33, 34, 35, 36, 36, 37, 38, 38, 38, 39, 39, 39, 39, 39, 38, 38, 38, 37, 36, 36, 35, 34, 33,
    32,
];

fn boot<D>(d: &mut D) -> Result<(), D::Error>
where
    D: DrawTarget<Color = BinaryColor>,
{
    // The name in an inverted banner, one period of the report's signature curve under it.
    d.fill_solid(&Rectangle::new(Point::new(34, 4), Size::new(60, 16)), ON)?;
    put(d, Cell::at(43, 7, 7).inverse(true), "inkstep")?;
    let mut prev: Option<Point> = None;
    for (i, &y) in BOOT_WAVE.iter().enumerate() {
        let x = 16 + 2 * i as i32;
        let p = Point::new(x, i32::from(y));
        widgets::line(d, prev.unwrap_or(p), p)?;
        prev = Some(p);
    }
    put(d, Cell::at(31, 42, 11), "pen plotter")?;
    put(d, Cell::at(9, 55, 22).small(), "STM32F103 + ST7920 LCD")
}

#[cfg(test)]
mod tests {
    use super::framebuffer::FrameBuffer;
    use super::*;
    use crate::hmi::{Config, MachineState};
    use crate::keypad::{Key, KeyEvent, KeyKind};

    fn press(hmi: &mut Hmi, st: &Status, key: Key, now: u32) {
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
        for (i, y) in ROW_Y.iter().enumerate() {
            assert_eq!(row_y(i), *y);
        }
    }

    #[test]
    fn text_helpers() {
        assert_eq!(dir_text([1, -1]).as_str(), "+X-Y");
        assert_eq!(dir_text([0, 1]).as_str(), "+Y");
        assert_eq!(dir_text([0, 0]).as_str(), "--");
        assert_eq!(time_text(12_345).as_str(), "12.3s");
        assert_eq!(time_text(125_000).as_str(), "2m05s");
        assert_eq!(axis_text('X', -12.345).as_str(), "X -12.35");
    }

    /// While drawing, a refresh sends only the changed cells and the new trace: far
    /// below the 10 Hz budget.
    #[test]
    fn drawing_refresh_is_a_small_fraction_of_a_full_frame() {
        let cfg = Config::default();
        let mut hmi = Hmi::new(cfg, 0);
        let mut st = Status::idle_at([0, 0, 500]);
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
        let st = Status::idle_at([0, 0, 500]);
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

    /// Rebuilding the drawing page (after an LCD reset) restores exactly what the
    /// incremental refreshes painted, trace included.
    #[test]
    fn rebuilt_drawing_page_matches_the_incremental_one() {
        let mut hmi = Hmi::new(Config::default(), 0);
        let mut st = Status::idle_at([0, 0, 500]);
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
