//! Snapshot tests: every LCD page rendered to PNG (4x, ST7920-like colours) and compared
//! pixel for pixel with the reference images in `tests/snapshots/`, so any change to a
//! screen shows up in review. `UPDATE_SNAPSHOTS=1 cargo test-host` rewrites them; a
//! missing or different snapshot fails, and the actual image is written next to the
//! test binary's temp dir for inspection.
//!
//! Also renders the keypad legend (`tests/snapshots/keypad_legend.png`) for the README.

use std::path::PathBuf;

use embedded_graphics::mono_font::{ascii, MonoTextStyle};
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{Line, PrimitiveStyle, Rectangle, RoundedRectangle, Triangle};
use embedded_graphics::text::{Alignment, Baseline, Text, TextStyleBuilder};

use inkstep_core::hmi::{Action, Config, Hmi, MachineState, Snapshot};
use inkstep_core::keypad::{Key, KeyEvent, KeyKind, KEYMAP, LEGEND};
use inkstep_core::screens::framebuffer::{FrameBuffer, HEIGHT, WIDTH};
use inkstep_core::screens::Screens;

const SCALE: usize = 4;
const MARGIN: usize = 8;
const GLASS: [u8; 3] = [166, 194, 74];
const GRID: [u8; 3] = [156, 184, 66];
/// The gap between two dark pixels is darker too, so solid areas read as solid.
const INK_GRID: [u8; 3] = [62, 80, 50];
const INK: [u8; 3] = [30, 46, 32];

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots")
}

/// Compare (or with UPDATE_SNAPSHOTS=1, write) `name`.png.
fn check_rgb(name: &str, w: usize, h: usize, rgb: &[u8]) {
    let path = dir().join(format!("{name}.png"));
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some_and(|v| v == "1") {
        std::fs::create_dir_all(dir()).unwrap();
        write_png(&path, w, h, rgb);
        return;
    }
    let actual = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.actual.png"));
    let Ok(bytes) = std::fs::read(&path) else {
        write_png(&actual, w, h, rgb);
        panic!(
            "missing snapshot {}; actual image in {} (UPDATE_SNAPSHOTS=1 to accept)",
            path.display(),
            actual.display()
        );
    };
    let (rw, rh, reference) = read_png(&bytes);
    if (rw, rh) != (w, h) || reference != rgb {
        write_png(&actual, w, h, rgb);
        let diff = reference
            .chunks(3)
            .zip(rgb.chunks(3))
            .filter(|(a, b)| a != b)
            .count();
        panic!(
            "snapshot {name} differs ({rw}x{rh} vs {w}x{h}, {diff} pixels); actual image in {} \
             (UPDATE_SNAPSHOTS=1 to accept)",
            actual.display()
        );
    }
}

fn write_png(path: &std::path::Path, w: usize, h: usize, rgb: &[u8]) {
    let file = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().unwrap();
    writer.write_image_data(rgb).unwrap();
}

fn read_png(bytes: &[u8]) -> (usize, usize, Vec<u8>) {
    let dec = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}

/// The frame buffer as an LCD photo: each pixel a 3x3 dot on a faint grid.
fn lcd_rgb(fb: &FrameBuffer) -> (usize, usize, Vec<u8>) {
    let w = WIDTH * SCALE + 2 * MARGIN;
    let h = HEIGHT * SCALE + 2 * MARGIN;
    let mut rgb = Vec::with_capacity(w * h * 3);
    for py in 0..h {
        for px in 0..w {
            let c = if px < MARGIN || py < MARGIN || px >= w - MARGIN || py >= h - MARGIN {
                GLASS
            } else {
                let (x, y) = ((px - MARGIN) / SCALE, (py - MARGIN) / SCALE);
                let edge = (px - MARGIN) % SCALE == SCALE - 1 || (py - MARGIN) % SCALE == SCALE - 1;
                match (fb.pixel(x, y), edge) {
                    (true, false) => INK,
                    (true, true) => INK_GRID,
                    (false, true) => GRID,
                    (false, false) => GLASS,
                }
            };
            rgb.extend_from_slice(&c);
        }
    }
    (w, h, rgb)
}

fn check(name: &str, fb: &FrameBuffer) {
    let (w, h, rgb) = lcd_rgb(fb);
    check_rgb(name, w, h, &rgb);
}

/// An HMI past the boot screen plus its status, screens and frame buffer.
struct Bench {
    hmi: Hmi,
    st: Snapshot,
    now: u32,
    screens: Screens,
    fb: FrameBuffer,
}

impl Bench {
    fn new() -> Self {
        let st = Snapshot::idle_at([1000, 400, 500]);
        let mut hmi = Hmi::new(Config::default(), 0);
        hmi.tick(&st, 2000);
        Bench {
            hmi,
            st,
            now: 2000,
            screens: Screens::new(),
            fb: FrameBuffer::new(),
        }
    }

    fn keys(&mut self, keys: &[Key]) {
        for &key in keys {
            self.now += 50;
            for kind in [KeyKind::Press, KeyKind::Release] {
                self.hmi.key(KeyEvent { key, kind }, &self.st, self.now);
            }
        }
    }

    fn number(&mut self, s: &str) {
        for c in s.chars() {
            let k = match c {
                '-' => Key::Sign,
                '.' => Key::Dot,
                d => Key::Digit(d.to_digit(10).unwrap() as u8),
            };
            self.keys(&[k]);
        }
    }

    fn tick(&mut self, ms: u32) {
        self.now += ms;
        self.hmi.tick(&self.st, self.now);
    }

    fn render(&mut self) {
        self.screens
            .render(&self.hmi, &self.st, self.now, &mut self.fb)
            .unwrap();
    }

    fn snap(&mut self, name: &str) {
        self.render();
        check(name, &self.fb);
    }
}

#[test]
fn boot() {
    let mut fb = FrameBuffer::new();
    let hmi = Hmi::new(Config::default(), 0);
    Screens::new()
        .render(&hmi, &Snapshot::idle_at([0; 3]), 0, &mut fb)
        .unwrap();
    check("boot", &fb);
}

#[test]
fn menu() {
    let mut b = Bench::new();
    b.snap("menu");
    b.keys(&[Key::Up, Key::Up, Key::Up]); // wraps to the last entries
    b.snap("menu_scrolled");
}

#[test]
fn machine_menu() {
    let mut b = Bench::new();
    b.keys(&[Key::Digit(9), Key::Down]);
    b.snap("machine_menu");
}

#[test]
fn jog() {
    let mut b = Bench::new();
    b.keys(&[Key::Digit(1), Key::Up]);
    b.hmi.key(
        KeyEvent {
            key: Key::Digit(3),
            kind: KeyKind::Press,
        },
        &b.st,
        b.now,
    );
    b.st.state = MachineState::Jog;
    b.st.pos = [2468, 1357, 500];
    b.tick(100);
    b.snap("jog");
}

#[test]
fn line_form_editing() {
    let mut b = Bench::new();
    b.keys(&[Key::Digit(2)]);
    b.number("-12.5");
    b.snap("form_line");
}

#[test]
fn sine_form_range_message() {
    let mut b = Bench::new();
    b.keys(&[Key::Digit(5), Key::Enter]);
    b.number("9");
    b.keys(&[Key::Enter]); // w = 9 rad/mm: above 5
    b.snap("form_sine_error");
}

/// Enter the sine form with A=10, w=0.3, phi=30, L=60 and reach the preview.
fn sine_preview(b: &mut Bench) {
    b.keys(&[Key::Digit(5)]);
    for v in ["10", "0.3", "30", "60"] {
        b.number(v);
        b.keys(&[Key::Enter]);
    }
}

#[test]
fn preview() {
    let mut b = Bench::new();
    sine_preview(&mut b);
    b.snap("preview_sine");
    let mut b = Bench::new();
    b.keys(&[Key::Digit(4), Key::Enter, Key::Enter]);
    b.snap("preview_ellipse");
}

/// Follow a job's ideal path to fraction `upto`, ticking and rendering as the firmware
/// would at 10 Hz.
fn draw_along(b: &mut Bench, upto: f32, steps: u32) {
    let inkstep_core::hmi::Page::Run(run) = *b.hmi.page() else {
        panic!("not drawing: {:?}", b.hmi.page());
    };
    b.st.state = MachineState::Run;
    b.st.queue_empty = false;
    b.st.feed_mm_min = 600.0;
    for i in 0..=steps {
        let t = upto * i as f32 / steps as f32;
        let p = run.job.point_at(t);
        let prev = b.st.pos;
        b.st.pos = [
            run.start[0] + (p[0] * 80.0).round() as i32,
            run.start[1] + (p[1] * 80.0).round() as i32,
            0,
        ];
        b.st.dir = [
            (b.st.pos[0] - prev[0]).signum() as i8,
            (b.st.pos[1] - prev[1]).signum() as i8,
        ];
        b.tick(100);
        b.render();
    }
}

#[test]
fn drawing_sine_with_trace() {
    let mut b = Bench::new();
    sine_preview(&mut b);
    b.keys(&[Key::Enter]);
    b.render();
    draw_along(&mut b, 0.62, 90);
    b.snap("run_sine");
}

#[test]
fn drawing_star_done() {
    let mut b = Bench::new();
    b.keys(&[Key::Digit(6), Key::Enter, Key::Enter]);
    b.render();
    let inkstep_core::hmi::Page::Run(run) = *b.hmi.page() else {
        panic!()
    };
    draw_along(&mut b, 1.0, 100);
    b.st = Snapshot {
        state: MachineState::Idle,
        queue_empty: true,
        pos: run.end,
        feed_mm_min: 0.0,
        dir: b.st.dir,
    };
    b.tick(100);
    b.snap("run_star_done");
}

#[test]
fn drawing_arc_on_hold() {
    let mut b = Bench::new();
    b.keys(&[Key::Digit(3)]);
    b.number("15");
    b.keys(&[Key::Enter]);
    b.number("-270");
    b.keys(&[Key::Enter, Key::Enter]);
    b.render();
    draw_along(&mut b, 0.4, 40);
    b.st.state = MachineState::Hold;
    b.st.feed_mm_min = 0.0;
    b.tick(100);
    b.snap("run_arc_hold");
}

/// G-code's M0 while the menu shows: the pause prompt with the last `(MSG, ...)`; D
/// answers it with cycle start.
#[test]
fn m0_prompt() {
    let mut b = Bench::new();
    b.st.state = MachineState::Hold;
    b.hmi
        .set_prompt(Some((None, b"Check the paper, then continue with pen 1")));
    b.snap("prompt_paused");
    let out = b.hmi.key(
        KeyEvent {
            key: Key::Enter,
            kind: KeyKind::Press,
        },
        &b.st,
        b.now,
    );
    assert_eq!(&out[..], &[Action::Resume]);
}

/// G-code's M6 T2 after `(MSG,pen 2: red)`: the pen-change prompt.
#[test]
fn m6_pen_change_prompt() {
    let mut b = Bench::new();
    b.st.state = MachineState::Hold;
    b.hmi.set_prompt(Some((Some(2), b"pen 2: red")));
    b.snap("prompt_pen_change");
}

#[test]
fn status_page() {
    let mut b = Bench::new();
    b.keys(&[Key::Digit(0), Key::Up]);
    b.snap("status");
}

#[test]
fn alarm_page() {
    let mut b = Bench::new();
    b.st.state = MachineState::Alarm(1);
    b.tick(100);
    b.snap("alarm");
}

#[test]
fn error_page() {
    let mut b = Bench::new();
    b.st.state = MachineState::Run; // a PC job is streaming
    b.keys(&[Key::Digit(1)]);
    b.snap("error_busy");
}

#[test]
fn abort_returns_to_menu_with_position() {
    let mut b = Bench::new();
    sine_preview(&mut b);
    b.keys(&[Key::Enter]);
    b.render();
    draw_along(&mut b, 0.3, 20);
    b.keys(&[Key::Back]);
    b.st.state = MachineState::Idle;
    b.st.queue_empty = true;
    b.tick(100);
    b.snap("menu_after_abort");
}

// ---------------------------------------------------------------------------------
// Keypad legend

struct Canvas {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
}

impl OriginDimensions for Canvas {
    fn size(&self) -> Size {
        Size::new(self.w as u32, self.h as u32)
    }
}

impl DrawTarget for Canvas {
    type Color = Rgb888;
    type Error = core::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(
        &mut self,
        it: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in it {
            if p.x >= 0 && p.y >= 0 && (p.x as usize) < self.w && (p.y as usize) < self.h {
                let i = (p.y as usize * self.w + p.x as usize) * 3;
                self.rgb[i..i + 3].copy_from_slice(&[c.r(), c.g(), c.b()]);
            }
        }
        Ok(())
    }
}

fn key_text(key: Key) -> (&'static str, &'static str) {
    match key {
        Key::Digit(5) => ("pen", "up/down"),
        Key::Digit(0) => ("", ""),
        Key::Digit(_) => ("", ""),
        Key::Sign => ("sign", "+/-"),
        Key::Dot => ("decimal", "point"),
        Key::Up => ("up", "speed +"),
        Key::Down => ("down", "speed -"),
        Key::Back => ("del/back", "abort"),
        Key::Enter => ("enter", "hold/go"),
    }
}

#[test]
fn keypad_legend() {
    const KW: i32 = 92;
    const KH: i32 = 70;
    const GAP: i32 = 10;
    const TOP: i32 = 34;
    let w = (4 * KW + 5 * GAP) as usize;
    let h = (TOP + 4 * KH + 4 * GAP + 30) as usize;
    let mut c = Canvas {
        w,
        h,
        rgb: vec![0; w * h * 3],
    };
    let bg = Rgb888::new(40, 44, 52);
    let digit_key = Rgb888::new(236, 236, 230);
    let fn_key = Rgb888::new(250, 204, 80);
    let ink = Rgb888::new(20, 20, 24);
    let jog = Rgb888::new(40, 110, 200);
    let white = Rgb888::new(240, 240, 240);
    c.clear(bg).unwrap();
    let center = TextStyleBuilder::new()
        .alignment(Alignment::Center)
        .baseline(Baseline::Top)
        .build();
    Text::with_text_style(
        "inkstep keypad (4x4)",
        Point::new(w as i32 / 2, 8),
        MonoTextStyle::new(&ascii::FONT_10X20, white),
        center,
    )
    .draw(&mut c)
    .unwrap();
    for (r, row) in KEYMAP.iter().enumerate() {
        for (col, key) in row.iter().enumerate() {
            let x = GAP + col as i32 * (KW + GAP);
            let y = TOP + GAP + r as i32 * (KH + GAP);
            let face = if matches!(key, Key::Digit(_)) {
                digit_key
            } else {
                fn_key
            };
            RoundedRectangle::with_equal_corners(
                Rectangle::new(Point::new(x, y), Size::new(KW as u32, KH as u32)),
                Size::new(8, 8),
            )
            .into_styled(PrimitiveStyle::with_fill(face))
            .draw(&mut c)
            .unwrap();
            Text::with_baseline(
                LEGEND[r][col],
                Point::new(x + 8, y + 6),
                MonoTextStyle::new(&ascii::FONT_10X20, ink),
                Baseline::Top,
            )
            .draw(&mut c)
            .unwrap();
            let small = MonoTextStyle::new(&ascii::FONT_7X13, ink);
            let (l1, l2) = key_text(*key);
            Text::with_baseline(l1, Point::new(x + 8, y + 32), small, Baseline::Top)
                .draw(&mut c)
                .unwrap();
            Text::with_baseline(l2, Point::new(x + 8, y + 48), small, Baseline::Top)
                .draw(&mut c)
                .unwrap();
            if let Some(d) = key.jog_dir() {
                // The jog arrow, pointing where the pen goes (+Y up).
                let ctr = Point::new(x + KW - 28, y + KH / 2 + 6);
                let (dx, dy) = (d[0] as f32, -(d[1] as f32));
                let n = (dx * dx + dy * dy).sqrt();
                let (ux, uy) = (dx / n, dy / n);
                let at = |a: f32, b: f32| {
                    Point::new(
                        ctr.x + (ux * a - uy * b).round() as i32,
                        ctr.y + (uy * a + ux * b).round() as i32,
                    )
                };
                Line::new(at(-18.0, 0.0), at(6.0, 0.0))
                    .into_styled(PrimitiveStyle::with_stroke(jog, 5))
                    .draw(&mut c)
                    .unwrap();
                Triangle::new(at(20.0, 0.0), at(4.0, 10.0), at(4.0, -10.0))
                    .into_styled(PrimitiveStyle::with_fill(jog))
                    .draw(&mut c)
                    .unwrap();
            }
        }
    }
    Text::with_text_style(
        "Jog: hold an arrow key to move, release to stop",
        Point::new(w as i32 / 2, h as i32 - 24),
        MonoTextStyle::new(&ascii::FONT_7X13, white),
        center,
    )
    .draw(&mut c)
    .unwrap();
    check_rgb("keypad_legend", w, h, &c.rgb);
}
