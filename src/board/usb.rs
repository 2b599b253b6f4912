//! The USB device and its CDC-ACM serial port, built in place in their 'static homes.

use core::mem::MaybeUninit;
use stm32f1xx_hal::usb::UsbBusType;
use usb_device::bus::UsbBusAllocator;
use usb_device::prelude::*;

pub type Usb = UsbDevice<'static, UsbBusType>;
/// The CDC serial port. Its receive store holds one 64-byte packet (the class default
/// is 128): both images read it with a 64-byte buffer, which empties it, and it takes
/// the next packet from the endpoint only once empty (until then the host is NAKed).
/// The transmit store keeps the default 128 bytes: it holds output while the endpoint
/// is busy, and bytes it refuses are dropped.
pub type UsbSerial =
    usbd_serial::SerialPort<'static, UsbBusType, [u8; 64], usbd_serial::DefaultBufferStore>;

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
