//! The USB full-speed device peripheral (RM0008 section 23): endpoint registers EPnR
//! with their toggle-on-write (DTOG, STAT) and clear-on-0 (CTR) bits, the 512-byte
//! packet memory seen by the CPU as 16-bit words at 32-bit strides, the buffer table
//! (BTABLE), CNTR/ISTR/FNR/DADDR, and the device side of each transaction: SETUP, OUT
//! and IN with ACK, NAK and STALL handshakes and DATA0/DATA1 toggles. The host side
//! (`crate::usb_host`) calls the transaction methods.
//!
//! Control endpoints: a SETUP is accepted whatever STAT_RX says, and sets both toggles
//! so that the data and status stages use DATA1 (23.4.2). A bus reset clears DADDR and
//! the endpoint registers. Double-buffered and isochronous endpoints are not modelled
//! (refused when configured).

use super::{unknown, Access, BusError};

pub const PMA_BYTES: usize = 512;

/// A device's answer to a host transaction.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Handshake {
    Ack,
    Nak,
    Stall,
    /// No answer (no such address or endpoint, or the device is off).
    Timeout,
}

pub struct Usb {
    pub epr: [u32; 8],
    pub cntr: u32,
    pub istr: u32,
    fnr: u32,
    pub daddr: u32,
    btable: u32,
    pub pma: [u8; PMA_BYTES],
}

const CTR_RX: u32 = 1 << 15;
const DTOG_RX: u32 = 1 << 14;
const STAT_RX: u32 = 3 << 12;
const SETUP: u32 = 1 << 11;
const CTR_TX: u32 = 1 << 7;
const DTOG_TX: u32 = 1 << 6;
const STAT_TX: u32 = 3 << 4;

const STALL: u32 = 1;
const NAK: u32 = 2;

impl Usb {
    pub fn new() -> Usb {
        Usb {
            epr: [0; 8],
            cntr: 3,
            istr: 0,
            fnr: 0,
            daddr: 0,
            btable: 0,
            pma: [0; PMA_BYTES],
        }
    }

    /// The pull-up and the transceiver are on (PDWN and FRES clear).
    pub fn powered(&self) -> bool {
        self.cntr & 3 == 0
    }

    /// Interrupt request on USB_LP_CAN_RX0: a flag in ISTR with its mask in CNTR.
    pub fn irq(&self) -> bool {
        self.istr_value() & self.cntr & 0xFF00 != 0
    }

    fn istr_value(&self) -> u32 {
        let mut v = self.istr & 0x7F00;
        if let Some(ep) = (0..8).find(|&i| self.epr[i] & (CTR_RX | CTR_TX) != 0) {
            v |= 1 << 15 | ep as u32;
            if self.epr[ep] & CTR_RX != 0 {
                v |= 1 << 4;
            }
        }
        v
    }

    fn pma_word(&self, at: usize) -> u16 {
        let at = at & (PMA_BYTES - 2);
        u16::from_le_bytes([self.pma[at], self.pma[at + 1]])
    }

    fn set_pma_word(&mut self, at: usize, v: u16) {
        let at = at & (PMA_BYTES - 2);
        self.pma[at..at + 2].copy_from_slice(&v.to_le_bytes());
    }

    fn bt(&self, ep: usize, field: usize) -> usize {
        self.btable as usize + 8 * ep + 2 * field
    }

    /// The CPU reads the packet memory at byte offset `off` of its 1 KB window.
    pub fn pma_read(&self, off: u32, size: usize) -> u32 {
        // Word i of the packet memory sits at window offset 4 i (the upper half of
        // each 32-bit slot is not backed and reads 0).
        let word = (off / 4) as usize * 2;
        let v = u32::from(self.pma_word(word));
        match (off % 4, size) {
            (0, 1) => v & 0xFF,
            (1, 1) => v >> 8,
            (0, _) => v,
            _ => 0,
        }
    }

    pub fn pma_write(&mut self, off: u32, size: usize, v: u32) {
        let word = (off / 4) as usize * 2;
        match (off % 4, size) {
            (0, 1) => {
                let w = (self.pma_word(word) & 0xFF00) | (v as u16 & 0xFF);
                self.set_pma_word(word, w);
            }
            (1, 1) => {
                let w = (self.pma_word(word) & 0x00FF) | ((v as u16 & 0xFF) << 8);
                self.set_pma_word(word, w);
            }
            (0, _) => self.set_pma_word(word, v as u16),
            _ => {}
        }
    }

    pub fn read(&self, off: u32) -> Access<u32> {
        Ok(match off {
            0x00..=0x1C => self.epr[(off / 4) as usize],
            0x40 => self.cntr,
            0x44 => self.istr_value(),
            0x48 => self.fnr,
            0x4C => self.daddr,
            0x50 => self.btable,
            _ => return Err(unknown("USB", off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access<()> {
        match off {
            0x00..=0x1C => {
                let i = (off / 4) as usize;
                let old = self.epr[i];
                let ty = (v >> 9) & 3;
                if ty == 2 || v & (1 << 8) != 0 && ty != 1 {
                    return Err(BusError(format!(
                        "USB EP{i}R 0x{v:04X}: isochronous or double-buffered endpoints are not modelled"
                    )));
                }
                // CTR bits: writing 0 clears, 1 keeps. DTOG and STAT: 1 toggles.
                let ctr = old & v & (CTR_RX | CTR_TX);
                let togglebits = DTOG_RX | STAT_RX | DTOG_TX | STAT_TX;
                let rw = v & 0x070F;
                self.epr[i] = ctr | (old & SETUP) | ((old ^ v) & togglebits) | rw;
            }
            0x40 => {
                self.cntr = v & 0xFF1F;
                if v & 1 != 0 {
                    // FRES: a forced reset, seen as a USB reset.
                    self.bus_reset_regs();
                }
            }
            0x44 => {
                // Flags are rc_w0; CTR, DIR and EP_ID are read-only.
                self.istr &= v | 0x80FF;
            }
            0x48 => {}
            0x4C => self.daddr = v & 0xFF,
            0x50 => self.btable = v & 0xFFF8,
            _ => return Err(unknown("USB", off)),
        }
        Ok(())
    }

    fn bus_reset_regs(&mut self) {
        self.epr = [0; 8];
        self.daddr = 0;
    }

    /// The host drives a bus reset: RESET in ISTR, address and endpoints cleared.
    pub fn bus_reset(&mut self) {
        if !self.powered() {
            return;
        }
        self.bus_reset_regs();
        self.istr |= 1 << 10;
    }

    /// Start of frame `n`.
    pub fn sof(&mut self, n: u32) {
        if !self.powered() {
            return;
        }
        self.fnr = n & 0x7FF;
        self.istr |= 1 << 9;
    }

    /// Three idle frames: SUSP.
    pub fn suspend(&mut self) {
        if self.powered() {
            self.istr |= 1 << 11;
        }
    }

    /// The endpoint register answering (address, endpoint), if any.
    fn endpoint(&self, addr: u8, ep: u8) -> Option<usize> {
        if !self.powered() || self.daddr & 0x80 == 0 || self.daddr & 0x7F != u32::from(addr) {
            return None;
        }
        (0..8).find(|&i| {
            let r = self.epr[i];
            r & 0xF == u32::from(ep) && (r & (STAT_RX | STAT_TX)) != 0
        })
    }

    fn rx_buffer(&self, i: usize) -> (usize, usize) {
        let addr = self.pma_word(self.bt(i, 2)) as usize;
        let count = self.pma_word(self.bt(i, 3));
        let blocks = usize::from((count >> 10) & 0x1F);
        let cap = if count & 0x8000 != 0 {
            32 * (blocks + 1)
        } else {
            2 * blocks
        };
        (addr, cap)
    }

    fn receive(&mut self, i: usize, data: &[u8]) -> bool {
        let (addr, cap) = self.rx_buffer(i);
        if data.len() > cap {
            // Babble: more than the buffer holds; the packet is not acknowledged.
            return false;
        }
        for (k, &b) in data.iter().enumerate() {
            self.pma[(addr + k) % PMA_BYTES] = b;
        }
        let count = self.pma_word(self.bt(i, 3));
        self.set_pma_word(self.bt(i, 3), (count & 0xFC00) | data.len() as u16);
        true
    }

    /// SETUP stage: 8 bytes to a control endpoint.
    pub fn setup(&mut self, addr: u8, ep: u8, data: &[u8; 8]) -> Handshake {
        let Some(i) = self.endpoint(addr, ep) else {
            return Handshake::Timeout;
        };
        let r = self.epr[i];
        if (r >> 9) & 3 != 1 || (r & STAT_RX) == 0 {
            return Handshake::Timeout;
        }
        if !self.receive(i, data) {
            return Handshake::Timeout;
        }
        // Accepted in any STAT_RX but DISABLED; both stages that follow use DATA1, and
        // both directions NAK until the software has looked at the request.
        let r = r | CTR_RX | SETUP | DTOG_RX | DTOG_TX;
        self.epr[i] = (r & !(STAT_RX | STAT_TX)) | (NAK << 12) | (NAK << 4);
        Handshake::Ack
    }

    /// OUT data stage or bulk OUT: a packet with toggle `data1`.
    pub fn out(&mut self, addr: u8, ep: u8, data1: bool, data: &[u8]) -> Handshake {
        let Some(i) = self.endpoint(addr, ep) else {
            return Handshake::Timeout;
        };
        let r = self.epr[i];
        match (r & STAT_RX) >> 12 {
            0 => return Handshake::Timeout,
            STALL => return Handshake::Stall,
            NAK => return Handshake::Nak,
            _ => {}
        }
        if (r & DTOG_RX != 0) != data1 {
            // A retransmission of a packet already taken: acknowledged, ignored.
            return Handshake::Ack;
        }
        if !self.receive(i, data) {
            return Handshake::Timeout;
        }
        let r = (r | CTR_RX) & !SETUP;
        self.epr[i] = ((r ^ DTOG_RX) & !STAT_RX) | (NAK << 12);
        Handshake::Ack
    }

    /// IN token: the packet with its toggle, or the handshake.
    pub fn in_token(&mut self, addr: u8, ep: u8) -> Result<(Vec<u8>, bool), Handshake> {
        let Some(i) = self.endpoint(addr, ep) else {
            return Err(Handshake::Timeout);
        };
        let r = self.epr[i];
        match (r & STAT_TX) >> 4 {
            0 => return Err(Handshake::Timeout),
            STALL => return Err(Handshake::Stall),
            NAK => return Err(Handshake::Nak),
            _ => {}
        }
        let addr_tx = self.pma_word(self.bt(i, 0)) as usize;
        let count = (self.pma_word(self.bt(i, 1)) & 0x3FF) as usize;
        let data = (0..count)
            .map(|k| self.pma[(addr_tx + k) % PMA_BYTES])
            .collect();
        let toggle = r & DTOG_TX != 0;
        self.epr[i] = (((r | CTR_TX) ^ DTOG_TX) & !STAT_TX) | (NAK << 4);
        Ok((data, toggle))
    }
}

impl Default for Usb {
    fn default() -> Self {
        Self::new()
    }
}
