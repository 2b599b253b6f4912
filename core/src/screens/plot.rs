//! The curve preview and the growing pen trace (the report's wish: "show the sine trace
//! on the LCD as the pen draws it").
//!
//! [`Plot`] fits a job's ideal path into a screen box (uniform scale, Y up) and draws it
//! dotted; [`Trace`] remembers the pen's pixel positions while drawing so the solid trace
//! can be extended one segment per refresh and redrawn whole if the screen is rebuilt.
//! The trace lives in a fixed array (no allocation); when it fills up every other point
//! is dropped, which keeps the shape at the preview's resolution.

use super::framebuffer::FrameBuffer;
use super::widgets::{line, Px};
use crate::decimal::round_i32;
use crate::hmi::job::Job;

/// A screen box: x, y, width, height in pixels.
pub type Area = [i32; 4];

/// Maps job millimetres (relative to the job start) to screen pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plot {
    area: Area,
    scale: f32,
    /// Pixel position of the job start (fractional).
    origin: [f32; 2],
}

impl Plot {
    /// Fit `job` inside `area` with a 2-pixel margin.
    pub fn fit(job: &Job, area: Area) -> Self {
        let [x, y, w, h] = area;
        let (lo, hi) = job.bounds();
        let bw = hi[0] - lo[0];
        let bh = hi[1] - lo[1];
        let sx = if bw > 1e-3 {
            (w - 5) as f32 / bw
        } else {
            f32::INFINITY
        };
        let sy = if bh > 1e-3 {
            (h - 5) as f32 / bh
        } else {
            f32::INFINITY
        };
        let mut scale = sx.min(sy);
        if !scale.is_finite() {
            scale = 1.0;
        }
        // Centre the drawing in the area (centre x + w / 2, exact in halves).
        let cx = (2 * x + w) as f32 * 0.5;
        let cy = (2 * y + h) as f32 * 0.5;
        let mid = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        Plot {
            area,
            scale,
            origin: [cx - mid[0] * scale, cy + mid[1] * scale],
        }
    }

    /// Pixels per mm.
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// Screen pixel of a point in mm (relative to the job start), clamped to the area.
    pub fn to_px(&self, mm: [f32; 2]) -> Px {
        let [x, y, w, h] = self.area;
        let px = self.origin[0] + mm[0] * self.scale;
        let py = self.origin[1] - mm[1] * self.scale;
        // Rounded; max/min rather than clamp: no "min > max" assertion to carry.
        let clamp = |v: f32, lo: i32, hi: i32| {
            if v.is_finite() {
                round_i32(v).max(lo).min(hi)
            } else {
                lo
            }
        };
        (clamp(px, x + 1, x + w - 2), clamp(py, y + 1, y + h - 2))
    }

    /// Draw the ideal path dotted (a pixel every ~2.5 px of path).
    pub fn draw_preview(&self, job: &Job, fb: &mut FrameBuffer) {
        let len_px = job.length_mm() * self.scale;
        let n = round_i32(len_px / 2.5).clamp(8, 400) as u32;
        for i in 0..n + 1 {
            let p = self.to_px(job.point_at(i as f32 / n as f32));
            fb.set(p.0, p.1, true);
        }
    }
}

/// Trace points kept for a full redraw.
pub const TRACE_POINTS: usize = 128;

/// The pen trace in screen pixels: the first `len` of `pts`.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    pts: [(u8, u8); TRACE_POINTS],
    len: usize,
}

impl Default for Trace {
    fn default() -> Self {
        Self::new()
    }
}

impl Trace {
    pub const fn new() -> Self {
        Trace {
            pts: [(0, 0); TRACE_POINTS],
            len: 0,
        }
    }

    pub fn clear(&mut self) {
        self.len = 0;
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn points(&self) -> &[(u8, u8)] {
        self.pts.get(..self.len).unwrap_or(&[])
    }

    fn last(&self) -> Option<Px> {
        self.points().last().map(|&(x, y)| (x as i32, y as i32))
    }

    /// Add the pen's pixel; returns the segment to draw (from the previous point), or
    /// None if the pixel did not change.
    pub fn push(&mut self, p: Px) -> Option<(Px, Px)> {
        let (x, y) = (p.0.clamp(0, 255) as u8, p.1.clamp(0, 255) as u8);
        let here = (x as i32, y as i32);
        let prev = self.last();
        if prev == Some(here) {
            return None;
        }
        if self.len >= TRACE_POINTS {
            // Keep every other point, and always the newest (in place).
            let n = self.len;
            let mut kept = 0;
            for i in 0..n {
                if i % 2 == 0 || i + 1 == n {
                    if let Some(&q) = self.pts.get(i) {
                        if let Some(slot) = self.pts.get_mut(kept) {
                            *slot = q;
                        }
                    }
                    kept += 1;
                }
            }
            self.len = kept;
        }
        if let Some(slot) = self.pts.get_mut(self.len) {
            *slot = (x, y);
            self.len += 1;
        }
        Some((prev.unwrap_or(here), here))
    }

    /// Draw the whole trace as connected lines.
    pub fn draw(&self, fb: &mut FrameBuffer) {
        let mut prev: Option<Px> = None;
        for &(x, y) in self.points() {
            let p = (x as i32, y as i32);
            line(fb, prev.unwrap_or(p), p);
            prev = Some(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(x: i32, y: i32) -> Px {
        (x, y)
    }

    #[test]
    fn plot_fits_the_job_inside_the_area_with_y_up() {
        let area = [2, 11, 72, 42];
        let job = Job::Sine {
            amp: 10.0,
            omega: 0.2,
            phase: 0.0,
            len: 60.0,
        };
        let plot = Plot::fit(&job, area);
        let start = plot.to_px([0.0, 0.0]);
        let end = plot.to_px(job.point_at(1.0));
        assert!(end.0 > start.0 + 50, "{start:?} {end:?}");
        let peak = plot.to_px(job.point_at(0.13)); // near the first maximum
        assert!(peak.1 < start.1, "Y up means smaller pixel rows");
        for i in 0..=50 {
            let p = plot.to_px(job.point_at(i as f32 / 50.0));
            assert!((2..74).contains(&p.0) && (11..53).contains(&p.1));
        }
    }

    #[test]
    fn trace_decimates_instead_of_overflowing() {
        let mut t = Trace::new();
        assert_eq!(t.push(pt(5, 5)), Some((pt(5, 5), pt(5, 5))));
        assert_eq!(t.push(pt(5, 5)), None);
        for i in 0..400 {
            t.push(pt(6 + i % 60, 5 + i / 60));
        }
        assert!(t.len() <= TRACE_POINTS);
        assert_eq!(t.last(), Some(pt(6 + 399 % 60, 5 + 399 / 60)));
    }
}
