//! The three fonts of the LCD, chosen for a 128x64 ST7920 (pixel pitch ~0.5 mm, slow
//! low-contrast STN glass viewed at arm's length on a bench):
//! - [`BODY`] 6x10 for values, menus and titles: 21 columns x 6 rows; its 7-pixel caps
//!   (about 3.5 mm on the glass) and open digits keep "8"/"0"/"6" apart at a glance,
//!   which matters most for live coordinates.
//! - [`SMALL`] 5x8 for hints, units and the message line: 25 columns, still clean
//!   glyphs with one pixel between characters. Nothing that must be read while the
//!   machine moves uses it.
//!
//! 4x6 was rejected: its digits are 3 pixels wide, "8", "0" and "B" blur together on
//! this panel, and STN response smear makes changing values unreadable. A 10x20 title
//! font was tried for the boot and alarm pages and dropped: 2.4 KB of flash for two
//! words; inverted 6x10 banners do the job.

use embedded_graphics::mono_font::{ascii, MonoFont};

pub const BODY: MonoFont<'static> = ascii::FONT_6X10;
pub const SMALL: MonoFont<'static> = ascii::FONT_5X8;
