//! The ST7920 128x64 graphic LCD controller on its serial interface (Sitronix ST7920
//! datasheet V4.0): chip select (RS pin) high frames the transfer; each instruction
//! or data byte is a start byte `11111 RW RS 0` and two bytes carrying the high and the
//! low nibble in their upper halves. Modelled: the basic and extended instruction
//! sets' control instructions, the graphic RAM (32 rows of 256 pixels; screen row r is
//! GDRAM row r words 0..7, row r + 32 is GDRAM row r words 8..15) with its
//! auto-incremented address, and the graphic display on/off. An instruction that
//! arrives before the previous one has executed (72 µs, 1.6 ms for clear) is lost, as
//! on the part, and counted. Text (DDRAM) writes are not modelled and stop the run.

use super::BusError;
use crate::clock::T_PER_US;

pub struct St7920 {
    /// Bytes of the frame being received.
    frame: Vec<u8>,
    /// Extended instruction set selected (RE).
    extended: bool,
    graphics_on: bool,
    display_on: bool,
    /// GDRAM address: two writes of `0x80 | a` (vertical first).
    addr_vertical: Option<u8>,
    row: usize,
    word: usize,
    /// The high byte of a GDRAM word waiting for its low byte.
    high: Option<u8>,
    pub gdram: [[u16; 16]; 32],
    busy_until: u64,
    /// Instructions that came while the controller was busy (lost).
    pub lost: u64,
    /// Every data byte written to GDRAM (a changed picture is a new frame).
    pub writes: u64,
}

impl St7920 {
    pub fn new() -> St7920 {
        St7920 {
            frame: Vec::new(),
            extended: false,
            graphics_on: false,
            display_on: false,
            addr_vertical: None,
            row: 0,
            word: 0,
            high: None,
            gdram: [[0; 16]; 32],
            busy_until: 0,
            lost: 0,
            writes: 0,
        }
    }

    /// Chip select went low: a partial frame is discarded.
    pub fn deselect(&mut self) {
        self.frame.clear();
    }

    /// A byte arrived on the serial input at time `t` with chip select high.
    pub fn byte(&mut self, t: u64, b: u8) -> Result<(), BusError> {
        if self.frame.is_empty() && b & 0xF8 != 0xF8 {
            // Not a start byte: ignored until one comes.
            return Ok(());
        }
        self.frame.push(b);
        if self.frame.len() < 3 {
            return Ok(());
        }
        let start = self.frame[0];
        let value = (self.frame[1] & 0xF0) | (self.frame[2] >> 4);
        self.frame.clear();
        if start & 4 != 0 {
            // RW = 1: reads are not possible in serial mode.
            return Ok(());
        }
        if t < self.busy_until {
            self.lost += 1;
            return Ok(());
        }
        let rs = start & 2 != 0;
        let exec_us = if rs {
            self.data(value)?
        } else {
            self.instruction(value)
        };
        self.busy_until = t + exec_us * T_PER_US;
        Ok(())
    }

    fn instruction(&mut self, i: u8) -> u64 {
        if i & 0x20 == 0x20 && i & 0xC0 == 0 {
            // Function set: RE (bit 2) and, in extended mode, G (bit 1).
            self.extended = i & 4 != 0;
            if self.extended {
                self.graphics_on = i & 2 != 0;
            }
            return 72;
        }
        if self.extended {
            if i & 0x80 != 0 {
                let a = i & 0x7F;
                match self.addr_vertical.take() {
                    None => self.addr_vertical = Some(a & 0x3F),
                    Some(v) => {
                        self.row = usize::from(v) % 32;
                        self.word = usize::from(a & 0x0F);
                        self.high = None;
                    }
                }
            }
            return 72;
        }
        match i {
            0x01 => {
                // Clear: DDRAM only (GDRAM is untouched); 1.6 ms.
                self.addr_vertical = None;
                return 1600;
            }
            0x02 | 0x03 => {}
            0x04..=0x07 => {}
            0x08..=0x0F => self.display_on = i & 4 != 0,
            _ => {}
        }
        72
    }

    fn data(&mut self, d: u8) -> Result<u64, BusError> {
        if !self.extended {
            return Err(BusError(
                "ST7920: text (DDRAM) writes are not modelled".into(),
            ));
        }
        self.writes += 1;
        match self.high.take() {
            None => self.high = Some(d),
            Some(h) => {
                self.gdram[self.row][self.word] = u16::from_be_bytes([h, d]);
                self.word = (self.word + 1) % 16;
            }
        }
        Ok(72)
    }

    /// Pixel (x, y) of the 128x64 screen as shown (dark when the display is off).
    pub fn pixel(&self, x: usize, y: usize) -> bool {
        if !(self.graphics_on && self.display_on) || x >= 128 || y >= 64 {
            return false;
        }
        let (row, word) = if y < 32 {
            (y, x / 16)
        } else {
            (y - 32, 8 + x / 16)
        };
        self.gdram[row][word] & (0x8000 >> (x % 16)) != 0
    }
}

impl Default for St7920 {
    fn default() -> Self {
        Self::new()
    }
}
