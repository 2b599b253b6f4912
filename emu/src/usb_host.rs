//! The PC side of the USB cable: a USB 2.0 host that sees the device attach (D+
//! pulled up: the Blue Pill's fixed 1.5 kΩ resistor, unless the firmware drives PA12
//! low), waits out the attach debounce (100 ms), resets the bus (10 ms) and lets it
//! recover (10 ms), enumerates it as an operating system does (device descriptor at
//! address 0, SET_ADDRESS, the descriptors, SET_CONFIGURATION), then acts as the
//! CDC-ACM class driver: SET_LINE_CODING (115200 8N1) and SET_CONTROL_LINE_STATE with
//! DTR and RTS while the port is open, bulk OUT packets from the sender's bytes and
//! bulk IN polling while the port is open.
//!
//! Timing model (emu/README.md): a start of frame every 1 ms; within a frame the host
//! controller gives each pipe (control, bulk OUT, bulk IN) one transaction attempt
//! every 125 µs, and retries a NAKed one at the next attempt.

use crate::clock::{T_PER_MS, T_PER_US};
use crate::periph::usb::{Handshake, Usb};
use std::collections::VecDeque;

pub const SLOT_T: u64 = 125 * T_PER_US;
const DEBOUNCE_T: u64 = 100 * T_PER_MS;
const RESET_T: u64 = 10 * T_PER_MS;
const RECOVERY_T: u64 = 10 * T_PER_MS;
/// Attempts without any answer before the host resets the bus again.
const GIVE_UP: u32 = 400;
const ADDRESS: u8 = 1;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Detached,
    Debounce(u64),
    Reset(u64),
    Recovery(u64),
    Enumerating,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Purpose {
    DeviceHead,
    SetAddress,
    Device,
    ConfigHead,
    Config,
    Strings,
    Product(u8),
    SetConfiguration,
    LineCoding,
    LineState(bool),
}

struct Control {
    setup: [u8; 8],
    out: Vec<u8>,
    purpose: Purpose,
    addr: u8,
    stage: Stage,
    got: Vec<u8>,
    toggle: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Setup,
    DataIn,
    DataOut(usize),
    StatusIn,
    StatusOut,
}

/// One USB packet on the bus, for timing figures.
#[derive(Clone, Debug)]
pub struct Packet {
    pub t: u64,
    pub out: bool,
    pub data: Vec<u8>,
}

pub struct Host {
    phase: Phase,
    next_slot: u64,
    next_sof: u64,
    frame: u32,
    addr: u8,
    mps0: usize,
    control: VecDeque<Control>,
    misses: u32,
    pub configured: bool,
    pub product: String,
    comm_interface: u8,
    bulk_in: Option<(u8, usize)>,
    bulk_out: Option<(u8, usize)>,
    in_toggle: bool,
    out_toggle: bool,
    /// The port is open (DTR and RTS on, IN polled).
    pub port_open: bool,
    dtr_sent: Option<bool>,
    /// Bytes the sender wrote, not yet sent.
    pub tx: VecDeque<u8>,
    /// Bytes the device sent, not yet read by the sender.
    pub rx: Vec<u8>,
    /// Every bulk packet, when recording.
    pub packets: Option<Vec<Packet>>,
    /// When enumeration finished.
    pub configured_at: Option<u64>,
    pub resets: u32,
}

fn setup(bm: u8, req: u8, value: u16, index: u16, len: u16) -> [u8; 8] {
    let v = value.to_le_bytes();
    let i = index.to_le_bytes();
    let l = len.to_le_bytes();
    [bm, req, v[0], v[1], i[0], i[1], l[0], l[1]]
}

impl Host {
    pub fn new() -> Host {
        Host {
            phase: Phase::Detached,
            next_slot: 0,
            next_sof: 0,
            frame: 0,
            addr: 0,
            mps0: 8,
            control: VecDeque::new(),
            misses: 0,
            configured: false,
            product: String::new(),
            comm_interface: 0,
            bulk_in: None,
            bulk_out: None,
            in_toggle: false,
            out_toggle: false,
            port_open: true,
            dtr_sent: None,
            tx: VecDeque::new(),
            rx: Vec::new(),
            packets: None,
            configured_at: None,
            resets: 0,
        }
    }

    /// When the host next does something.
    pub fn next_event(&self) -> u64 {
        match self.phase {
            Phase::Detached => u64::MAX,
            Phase::Debounce(t) | Phase::Reset(t) | Phase::Recovery(t) => t,
            Phase::Enumerating => self.next_slot,
        }
    }

    /// The device's D+ line changed (attached when pulled up).
    pub fn set_attached(&mut self, attached: bool, now: u64) {
        match (attached, self.phase) {
            (false, Phase::Detached) => {}
            (false, _) => self.detach(),
            (true, Phase::Detached) => self.phase = Phase::Debounce(now + DEBOUNCE_T),
            (true, _) => {}
        }
    }

    fn detach(&mut self) {
        let keep = (std::mem::take(&mut self.tx), std::mem::take(&mut self.rx));
        let packets = self.packets.take();
        let open = self.port_open;
        let resets = self.resets;
        *self = Host::new();
        (self.tx, self.rx) = keep;
        self.packets = packets;
        self.port_open = open;
        self.resets = resets;
    }

    fn start_enumeration(&mut self, now: u64) {
        self.phase = Phase::Enumerating;
        self.next_slot = now;
        self.next_sof = now;
        self.addr = 0;
        self.configured = false;
        self.control.clear();
        self.misses = 0;
        self.push(0x80, 6, 0x0100, 0, 64, Purpose::DeviceHead, 0);
    }

    #[allow(clippy::too_many_arguments)] // the SETUP packet's five fields, plus who asks
    fn push(
        &mut self,
        bm: u8,
        req: u8,
        value: u16,
        index: u16,
        len: u16,
        purpose: Purpose,
        addr: u8,
    ) {
        self.push_out(setup(bm, req, value, index, len), Vec::new(), purpose, addr);
    }

    fn push_out(&mut self, setup: [u8; 8], out: Vec<u8>, purpose: Purpose, addr: u8) {
        self.control.push_back(Control {
            setup,
            out,
            purpose,
            addr,
            stage: Stage::Setup,
            got: Vec::new(),
            toggle: true,
        });
    }

    /// Do everything due up to `now`.
    pub fn advance(&mut self, now: u64, dev: &mut Usb) {
        loop {
            match self.phase {
                Phase::Detached => return,
                Phase::Debounce(t) if t <= now => {
                    self.phase = Phase::Reset(t + RESET_T);
                    self.resets += 1;
                    dev.bus_reset();
                }
                Phase::Reset(t) if t <= now => self.phase = Phase::Recovery(t + RECOVERY_T),
                Phase::Recovery(t) if t <= now => self.start_enumeration(t),
                Phase::Enumerating if self.next_slot <= now => {
                    let t = self.next_slot;
                    if t >= self.next_sof {
                        dev.sof(self.frame);
                        self.frame = self.frame.wrapping_add(1);
                        self.next_sof += T_PER_MS;
                    }
                    self.slot(t, dev);
                    self.next_slot += SLOT_T;
                }
                _ => return,
            }
        }
    }

    fn slot(&mut self, t: u64, dev: &mut Usb) {
        if self.configured {
            if self.dtr_sent != Some(self.port_open) && self.control.is_empty() {
                let v = if self.port_open { 3 } else { 0 };
                let iface = u16::from(self.comm_interface);
                self.push(
                    0x21,
                    0x22,
                    v,
                    iface,
                    0,
                    Purpose::LineState(self.port_open),
                    ADDRESS,
                );
                self.dtr_sent = Some(self.port_open);
            }
            self.bulk(t, dev);
        }
        self.control_slot(dev);
    }

    fn bulk(&mut self, t: u64, dev: &mut Usb) {
        if let Some((ep, mps)) = self.bulk_out {
            if !self.tx.is_empty() {
                let n = self.tx.len().min(mps);
                let chunk: Vec<u8> = self.tx.iter().take(n).copied().collect();
                if dev.out(self.addr, ep, self.out_toggle, &chunk) == Handshake::Ack {
                    self.tx.drain(..n);
                    self.out_toggle = !self.out_toggle;
                    if let Some(p) = &mut self.packets {
                        p.push(Packet {
                            t,
                            out: true,
                            data: chunk,
                        });
                    }
                }
            }
        }
        if let Some((ep, _)) = self.bulk_in {
            if self.port_open {
                if let Ok((data, toggle)) = dev.in_token(self.addr, ep) {
                    if toggle == self.in_toggle {
                        self.in_toggle = !self.in_toggle;
                        if let Some(p) = &mut self.packets {
                            p.push(Packet {
                                t,
                                out: false,
                                data: data.clone(),
                            });
                        }
                        self.rx.extend_from_slice(&data);
                    }
                }
            }
        }
    }

    fn control_slot(&mut self, dev: &mut Usb) {
        let mps0 = self.mps0;
        let Some(c) = self.control.front_mut() else {
            return;
        };
        let len = usize::from(u16::from_le_bytes([c.setup[6], c.setup[7]]));
        let device_to_host = c.setup[0] & 0x80 != 0;
        let answer = match c.stage {
            Stage::Setup => {
                let h = dev.setup(c.addr, 0, &c.setup);
                if h == Handshake::Ack {
                    c.toggle = true;
                    c.stage = if len == 0 {
                        Stage::StatusIn
                    } else if device_to_host {
                        Stage::DataIn
                    } else {
                        Stage::DataOut(0)
                    };
                }
                h
            }
            Stage::DataIn => match dev.in_token(c.addr, 0) {
                Ok((data, toggle)) => {
                    if toggle == c.toggle {
                        c.toggle = !c.toggle;
                        let short = data.len() < mps0;
                        c.got.extend_from_slice(&data);
                        if short || c.got.len() >= len {
                            c.got.truncate(len);
                            c.stage = Stage::StatusOut;
                        }
                    }
                    Handshake::Ack
                }
                Err(h) => h,
            },
            Stage::DataOut(at) => {
                let end = (at + mps0).min(c.out.len());
                let h = dev.out(c.addr, 0, c.toggle, &c.out[at..end]);
                if h == Handshake::Ack {
                    c.toggle = !c.toggle;
                    c.stage = if end >= c.out.len() {
                        Stage::StatusIn
                    } else {
                        Stage::DataOut(end)
                    };
                }
                h
            }
            Stage::StatusIn => match dev.in_token(c.addr, 0) {
                Ok(_) => {
                    self.finish(dev);
                    Handshake::Ack
                }
                Err(h) => h,
            },
            Stage::StatusOut => {
                let h = dev.out(c.addr, 0, true, &[]);
                if h == Handshake::Ack {
                    self.finish(dev);
                }
                h
            }
        };
        match answer {
            Handshake::Timeout => {
                self.misses += 1;
                if self.misses > GIVE_UP {
                    // The device stopped answering: reset the bus and start over.
                    self.phase = Phase::Reset(self.next_slot + RESET_T);
                    self.resets += 1;
                    self.configured = false;
                    dev.bus_reset();
                }
            }
            Handshake::Stall => {
                // A request the device does not support: dropped, enumeration goes on.
                self.misses = 0;
                self.control.pop_front();
            }
            _ => self.misses = 0,
        }
    }

    fn finish(&mut self, _dev: &mut Usb) {
        let Some(c) = self.control.pop_front() else {
            return;
        };
        let d = &c.got;
        match c.purpose {
            Purpose::DeviceHead => {
                self.mps0 = usize::from(d.get(7).copied().unwrap_or(8)).max(8);
                self.push(0x00, 5, u16::from(ADDRESS), 0, 0, Purpose::SetAddress, 0);
            }
            Purpose::SetAddress => {
                self.addr = ADDRESS;
                self.push(0x80, 6, 0x0100, 0, 18, Purpose::Device, ADDRESS);
            }
            Purpose::Device => {
                let product = d.get(15).copied().unwrap_or(0);
                self.push(0x80, 6, 0x0200, 0, 9, Purpose::ConfigHead, ADDRESS);
                self.push(0x80, 6, 0x0300, 0, 255, Purpose::Strings, ADDRESS);
                if product != 0 {
                    self.push(
                        0x80,
                        6,
                        0x0300 | u16::from(product),
                        0x0409,
                        255,
                        Purpose::Product(product),
                        ADDRESS,
                    );
                }
            }
            Purpose::ConfigHead => {
                let total = u16::from_le_bytes([
                    d.get(2).copied().unwrap_or(9),
                    d.get(3).copied().unwrap_or(0),
                ]);
                self.push(0x80, 6, 0x0200, 0, total, Purpose::Config, ADDRESS);
            }
            Purpose::Config => {
                self.parse_config(d);
                let value = u16::from(d.get(5).copied().unwrap_or(1));
                self.push(0x00, 9, value, 0, 0, Purpose::SetConfiguration, ADDRESS);
            }
            Purpose::Strings => {}
            Purpose::Product(_) => {
                let units: Vec<u16> = d
                    .get(2..)
                    .unwrap_or(&[])
                    .chunks_exact(2)
                    .map(|p| u16::from_le_bytes([p[0], p[1]]))
                    .collect();
                self.product = String::from_utf16_lossy(&units);
            }
            Purpose::SetConfiguration => {
                // 115200 baud, 1 stop bit, no parity, 8 data bits.
                let coding = vec![0x00, 0xC2, 0x01, 0x00, 0, 0, 8];
                let iface = u16::from(self.comm_interface);
                self.push_out(
                    setup(0x21, 0x20, 0, iface, 7),
                    coding,
                    Purpose::LineCoding,
                    ADDRESS,
                );
            }
            Purpose::LineCoding => {
                self.configured = true;
                self.in_toggle = false;
                self.out_toggle = false;
                self.configured_at = Some(self.next_slot);
            }
            Purpose::LineState(_) => {}
        }
    }

    fn parse_config(&mut self, d: &[u8]) {
        let mut i = 0;
        let mut class = 0;
        let mut iface = 0;
        while i + 1 < d.len() {
            let len = usize::from(d[i]);
            if len < 2 || i + len > d.len() {
                break;
            }
            let desc = &d[i..i + len];
            match desc[1] {
                4 if len >= 9 => {
                    iface = desc[2];
                    class = desc[5];
                    if class == 2 {
                        self.comm_interface = iface;
                    }
                }
                5 if len >= 7 => {
                    let ep = desc[2];
                    let mps = usize::from(u16::from_le_bytes([desc[4], desc[5]]));
                    if desc[3] & 3 == 2 && class == 0x0A {
                        if ep & 0x80 != 0 {
                            self.bulk_in = Some((ep & 0x0F, mps));
                        } else {
                            self.bulk_out = Some((ep & 0x0F, mps));
                        }
                    }
                }
                _ => {}
            }
            i += len;
        }
        let _ = iface;
    }
}

impl Default for Host {
    fn default() -> Self {
        Self::new()
    }
}
