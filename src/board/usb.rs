//! The USB device and its CDC-ACM serial port, built in place in their 'static homes,
//! and the port's data stream, moved one packet at a time between the class's bulk
//! endpoints and the firmware's byte rings.

use core::mem::MaybeUninit;
use inkstep_core::ring::ByteRx;
use stm32f1xx_hal::usb::UsbBusType;
use usb_device::bus::UsbBusAllocator;
use usb_device::prelude::*;
use usbd_serial::CdcAcmClass;

pub type Usb = UsbDevice<'static, UsbBusType>;

/// Bytes in one packet of the data endpoints (full-speed bulk).
pub const USB_PACKET: usize = 64;
/// After this many full packets in a row the next is sent one byte short: a host that
/// asked for more bytes than the stream holds gets what came so far (the rule of
/// usbd-serial's `SerialPort`, whose buffering this port replaces).
const FULL_RUN_MAX: u8 = 10;

/// The CDC-ACM serial port: usbd-serial's class (descriptors, control requests, DTR)
/// with the data moved straight between its endpoints and the byte rings the tasks
/// share. usbd-serial's `SerialPort` would put a second pair of buffers
/// in front of those rings, and a copy of every byte through them.
pub struct UsbSerial {
    class: CdcAcmClass<'static, UsbBusType>,
    /// Full packets sent in a row: a transfer that ends on a full packet is closed by
    /// a zero-length one.
    full_run: u8,
}

impl UsbSerial {
    pub(super) fn new(bus: &'static UsbBusAllocator<UsbBusType>) -> Self {
        Self {
            class: CdcAcmClass::new(bus, USB_PACKET as u16),
            full_run: 0,
        }
    }

    /// The class, for the device's poll.
    pub fn class(&mut self) -> &mut CdcAcmClass<'static, UsbBusType> {
        &mut self.class
    }

    /// The host has the port open (DTR).
    pub fn dtr(&self) -> bool {
        self.class.dtr()
    }

    /// The packet the host sent, if one waits; how many bytes it had (0: none). Until
    /// it is read the endpoint NAKs the host's next packet.
    pub fn read_packet(&mut self, buf: &mut [u8; USB_PACKET]) -> usize {
        self.class.read_packet(buf).unwrap_or(0)
    }

    /// Queued output from `tx`, one packet when the endpoint is free (the next goes on
    /// the next USB interrupt, which this packet's completion raises). Bytes leave
    /// `tx` only once the endpoint took them.
    pub fn send<const N: usize>(&mut self, tx: &mut ByteRx<'_, N>) {
        if tx.is_empty() && self.full_run == 0 {
            return;
        }
        let mut buf = [0u8; USB_PACKET];
        let max = USB_PACKET - usize::from(self.full_run >= FULL_RUN_MAX);
        // Nothing queued after full packets: a zero-length packet ends the transfer.
        let n = tx.peek_into(buf.get_mut(..max).unwrap_or(&mut []));
        if self.class.write_packet(buf.get(..n).unwrap_or(&[])).is_ok() {
            tx.skip(n);
            self.full_run = if n == USB_PACKET {
                self.full_run + 1
            } else {
                0
            };
        }
    }
}

/// The 'static homes of the USB stack (an RTIC init local): the bus allocator the
/// device and the class borrow, and the device and the serial port themselves, built
/// in place and handed out by reference rather than moved through `init`.
pub struct UsbCells {
    pub(super) bus: MaybeUninit<UsbBusAllocator<UsbBusType>>,
    pub(super) dev: MaybeUninit<Usb>,
    pub(super) serial: MaybeUninit<UsbSerial>,
}

impl UsbCells {
    pub const fn new() -> Self {
        Self {
            bus: MaybeUninit::uninit(),
            dev: MaybeUninit::uninit(),
            serial: MaybeUninit::uninit(),
        }
    }
}

impl Default for UsbCells {
    fn default() -> Self {
        Self::new()
    }
}
