//! The curve preview and the growing pen trace (the report's wish: "show the sine trace
//! on the LCD as the pen draws it").
//!
//! [`Plot`] fits a job's ideal path into a screen box (uniform scale, Y up) and draws it
//! dotted; [`Trace`] remembers the pen's pixel positions while drawing so the solid trace
//! can be extended one segment per refresh and redrawn whole if the screen is rebuilt.
//! The trace lives in a fixed array (no allocation); when it fills up every other point
//! is dropped, which keeps the shape at the preview's resolution.

use crate::fmath;
use embedded_graphics::pixelcolor::BinaryColor;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::Rectangle;
use heapless::Vec;

use super::widgets::line;
use crate::hmi::job::Job;

/// Maps job millimetres (relative to the job start) to screen pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plot {
    area: Rectangle,
    scale: f32,
    /// Pixel position of the job start (fractional).
    origin: [f32; 2],
}

impl Plot {
    /// Fit `job` inside `area` with a 2-pixel margin.
    pub fn fit(job: &Job, area: Rectangle) -> Self {
        let (lo, hi) = job.bounds();
        let inner_w = area.size.width.saturating_sub(5) as f32;
        let inner_h = area.size.height.saturating_sub(5) as f32;
        let w = hi[0] - lo[0];
        let h = hi[1] - lo[1];
        let sx = if w > 1e-3 { inner_w / w } else { f32::INFINITY };
        let sy = if h > 1e-3 { inner_h / h } else { f32::INFINITY };
        let mut scale = sx.min(sy);
        if !scale.is_finite() {
            scale = 1.0;
        }
        // Centre the drawing in the area.
        let cx = area.top_left.x as f32 + area.size.width as f32 / 2.0;
        let cy = area.top_left.y as f32 + area.size.height as f32 / 2.0;
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
    pub fn to_px(&self, mm: [f32; 2]) -> Point {
        let x = fmath::round(self.origin[0] + mm[0] * self.scale);
        let y = fmath::round(self.origin[1] - mm[1] * self.scale);
        let br = self.area.top_left + self.area.size - Point::new(2, 2);
        let tl = self.area.top_left + Point::new(1, 1);
        // max/min rather than clamp: no "min > max" assertion to carry.
        let clamp = |v: f32, lo: i32, hi: i32| {
            if v.is_finite() {
                (v as i32).max(lo).min(hi)
            } else {
                lo
            }
        };
        Point::new(clamp(x, tl.x, br.x), clamp(y, tl.y, br.y))
    }

    /// Draw the ideal path dotted (a pixel every ~2.5 px of path).
    pub fn draw_preview<D>(&self, job: &Job, d: &mut D) -> Result<(), D::Error>
    where
        D: DrawTarget<Color = BinaryColor>,
    {
        let len_px = job.length_mm() * self.scale;
        let n = fmath::round(len_px / 2.5).clamp(8.0, 400.0) as u32;
        for i in 0..n + 1 {
            let p = self.to_px(job.point_at(i as f32 / n as f32));
            Pixel(p, BinaryColor::On).draw(d)?;
        }
        Ok(())
    }
}

/// Trace points kept for a full redraw.
pub const TRACE_POINTS: usize = 128;

/// The pen trace in screen pixels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    pts: Vec<(u8, u8), TRACE_POINTS>,
}

impl Trace {
    pub fn new() -> Self {
        Trace { pts: Vec::new() }
    }

    pub fn clear(&mut self) {
        self.pts.clear();
    }

    pub fn len(&self) -> usize {
        self.pts.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pts.is_empty()
    }

    fn last(&self) -> Option<Point> {
        self.pts
            .last()
            .map(|&(x, y)| Point::new(x as i32, y as i32))
    }

    /// Add the pen's pixel; returns the segment to draw (from the previous point), or
    /// None if the pixel did not change.
    pub fn push(&mut self, p: Point) -> Option<(Point, Point)> {
        let (x, y) = (p.x.clamp(0, 255) as u8, p.y.clamp(0, 255) as u8);
        let prev = self.last();
        if prev == Some(Point::new(x as i32, y as i32)) {
            return None;
        }
        if self.pts.is_full() {
            // Keep every other point, and always the newest.
            let mut kept: Vec<(u8, u8), TRACE_POINTS> = Vec::new();
            let n = self.pts.len();
            for (i, q) in self.pts.iter().enumerate() {
                if i % 2 == 0 || i + 1 == n {
                    let _ = kept.push(*q);
                }
            }
            self.pts = kept;
        }
        let _ = self.pts.push((x, y));
        let here = Point::new(x as i32, y as i32);
        Some((prev.unwrap_or(here), here))
    }

    /// Draw the whole trace as connected lines.
    pub fn draw<D>(&self, d: &mut D) -> Result<(), D::Error>
    where
        D: DrawTarget<Color = BinaryColor>,
    {
        let mut prev: Option<Point> = None;
        for &(x, y) in &self.pts {
            let p = Point::new(x as i32, y as i32);
            line(d, prev.unwrap_or(p), p)?;
            prev = Some(p);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_fits_the_job_inside_the_area_with_y_up() {
        let area = Rectangle::new(Point::new(2, 11), Size::new(72, 42));
        let job = Job::Sine {
            amp: 10.0,
            omega: 0.2,
            phase: 0.0,
            len: 60.0,
        };
        let plot = Plot::fit(&job, area);
        let start = plot.to_px([0.0, 0.0]);
        let end = plot.to_px(job.point_at(1.0));
        assert!(end.x > start.x + 50, "{start:?} {end:?}");
        let peak = plot.to_px(job.point_at(0.13)); // near the first maximum
        assert!(peak.y < start.y, "Y up means smaller pixel rows");
        for i in 0..=50 {
            let p = plot.to_px(job.point_at(i as f32 / 50.0));
            assert!(area.contains(p));
        }
    }

    #[test]
    fn trace_decimates_instead_of_overflowing() {
        let mut t = Trace::new();
        assert_eq!(
            t.push(Point::new(5, 5)),
            Some((Point::new(5, 5), Point::new(5, 5)))
        );
        assert_eq!(t.push(Point::new(5, 5)), None);
        for i in 0..400 {
            t.push(Point::new(6 + i % 60, 5 + i / 60));
        }
        assert!(t.len() <= TRACE_POINTS);
        assert_eq!(t.last(), Some(Point::new(6 + 399 % 60, 5 + 399 / 60)));
    }
}
