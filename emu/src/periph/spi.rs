//! SPI in master mode (RM0008 section 25.3.3, 25.5): the transmit buffer and the shift
//! register, TXE, RXNE, BSY and OVR, the baud-rate prescaler, 8- and 16-bit frames.
//! Each frame leaves the shift register 8 (or 16) SCK periods after it entered it and
//! is handed to the device on the bus; MISO is not wired on this board, so the
//! received frames are 0. The transmit DMA request (TXE with TXDMAEN) goes to DMA1
//! channel 5 (`board.rs`). Slave mode, CRC, I2S and receive DMA are refused.

use super::{unknown, Access, BusError};

pub struct Spi {
    name: &'static str,
    cr1: u32,
    cr2: u32,
    sr: u32,
    /// Frame waiting in the transmit buffer.
    tx_buf: Option<u16>,
    /// Frame in the shift register and when it is out.
    shifting: Option<(u16, u64)>,
    rx: u16,
    crcpr: u32,
    /// Time units per bus clock cycle.
    pub pclk_t: u64,
}

const TXE: u32 = 1 << 1;
const RXNE: u32 = 1 << 0;
const OVR: u32 = 1 << 6;
const BSY: u32 = 1 << 7;
const RXDMAEN: u32 = 1 << 0;
const TXDMAEN: u32 = 1 << 1;

impl Spi {
    pub fn new(name: &'static str) -> Spi {
        Spi {
            name,
            cr1: 0,
            cr2: 0,
            sr: TXE,
            tx_buf: None,
            shifting: None,
            rx: 0,
            crcpr: 7,
            pclk_t: 1,
        }
    }

    pub fn reset(&mut self) {
        let pclk_t = self.pclk_t;
        *self = Spi::new(self.name);
        self.pclk_t = pclk_t;
    }

    fn frame_t(&self) -> u64 {
        let div = 2u64 << ((self.cr1 >> 3) & 7);
        let bits = if self.cr1 & (1 << 11) != 0 { 16 } else { 8 };
        bits * div * self.pclk_t
    }

    pub fn next_event(&self) -> Option<u64> {
        self.shifting.map(|(_, t)| t)
    }

    /// Frames that finished shifting out by `now`, in order.
    pub fn advance(&mut self, now: u64, out: &mut Vec<(u64, u16)>) {
        while let Some((frame, t)) = self.shifting {
            if t > now {
                break;
            }
            out.push((t, frame));
            if self.sr & RXNE != 0 {
                self.sr |= OVR;
            } else {
                self.rx = 0;
                self.sr |= RXNE;
            }
            self.shifting = None;
            self.load(t);
        }
        self.status();
    }

    fn load(&mut self, t: u64) {
        if self.shifting.is_none() && self.cr1 & (1 << 6) != 0 {
            if let Some(f) = self.tx_buf.take() {
                self.shifting = Some((f, t + self.frame_t()));
            }
        }
        self.status();
    }

    fn status(&mut self) {
        if self.tx_buf.is_none() {
            self.sr |= TXE;
        } else {
            self.sr &= !TXE;
        }
        if self.shifting.is_some() || self.tx_buf.is_some() {
            self.sr |= BSY;
        } else {
            self.sr &= !BSY;
        }
    }

    /// The transmit DMA request (CR2.TXDMAEN): raised while the transmit buffer is
    /// empty, dropped by the write of DR that fills it (25.3.9).
    pub fn tx_dma_request(&self) -> bool {
        self.cr2 & TXDMAEN != 0 && self.sr & TXE != 0
    }

    pub fn irq(&self) -> bool {
        (self.cr2 & (1 << 7) != 0 && self.sr & TXE != 0)
            || (self.cr2 & (1 << 6) != 0 && self.sr & RXNE != 0)
            || (self.cr2 & (1 << 5) != 0 && self.sr & OVR != 0)
    }

    pub fn read(&mut self, off: u32) -> Access<u32> {
        Ok(match off {
            0x00 => self.cr1,
            0x04 => self.cr2,
            0x08 => self.sr,
            0x0C => {
                self.sr &= !RXNE;
                // Reading DR after SR clears OVR (25.4.8).
                self.sr &= !OVR;
                u32::from(self.rx)
            }
            0x10 => self.crcpr,
            0x14 | 0x18 | 0x1C => 0,
            0x20 => 2,
            _ => return Err(unknown(self.name, off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32, now: u64) -> Access<()> {
        match off {
            0x00 => {
                if v & (1 << 13) != 0 {
                    return Err(BusError(format!("{}: CRC is not modelled", self.name)));
                }
                if v & (1 << 6) != 0 && v & (1 << 2) == 0 {
                    return Err(BusError(format!(
                        "{}: slave mode is not modelled",
                        self.name
                    )));
                }
                self.cr1 = v & 0xFFFF;
                self.load(now);
            }
            0x04 => {
                if v & RXDMAEN != 0 {
                    return Err(BusError(format!(
                        "{}: receive DMA is not modelled",
                        self.name
                    )));
                }
                self.cr2 = v & 0xE7;
            }
            0x08 => {
                // CRCERR is the only writable flag (rc_w0).
                self.sr &= !(!v & 0x10);
            }
            0x0C => {
                // A frame written while the buffer is full overwrites it (the
                // software's mistake; the hardware does the same).
                self.tx_buf = Some(v as u16);
                self.load(now);
            }
            0x10 => self.crcpr = v & 0xFFFF,
            0x1C => {
                if v & (1 << 11) != 0 {
                    return Err(BusError(format!("{}: I2S is not modelled", self.name)));
                }
            }
            0x20 => {}
            _ => return Err(unknown(self.name, off)),
        }
        Ok(())
    }
}
