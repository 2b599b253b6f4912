//! The client side: a serial port (the board's /dev/ttyACM0, or a pty that
//! `cargo sim serve` / `cargo emu serve` opened) as a byte pipe for the sender, and
//! the list of ports the system knows.
//!
//! The [`Transport`] trait is what the sender's drivers talk to, so tests can put an
//! in-process fake controller in its place.

use std::io::{self, Read, Write};
use std::time::Duration;

/// A byte pipe to the controller.
pub trait Transport {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Receives what has arrived, waiting only briefly; 0 when nothing did.
    fn recv(&mut self, buf: &mut [u8]) -> io::Result<usize>;
}

/// An open serial port; reads wait at most 10 ms.
pub struct Port(Box<dyn serialport::SerialPort>);

impl Port {
    pub fn open(path: &str, baud: u32) -> io::Result<Port> {
        serialport::new(path, baud)
            .timeout(Duration::from_millis(10))
            .open()
            .map(Port)
            .map_err(io::Error::from)
    }
}

impl Transport for Port {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.0.write_all(bytes)?;
        loop {
            match self.0.flush() {
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                r => return r,
            }
        }
    }

    fn recv(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self.0.read(buf) {
            // A pty whose server went away reads 0 bytes for ever: that is a hang-up.
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "the port was closed by the other side",
            )),
            Ok(n) => Ok(n),
            // A timeout is just "nothing yet"; EINTR comes with Ctrl-C, which the
            // drivers handle through their stop flags.
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut
                        | io::ErrorKind::WouldBlock
                        | io::ErrorKind::Interrupted
                ) =>
            {
                Ok(0)
            }
            Err(e) => Err(e),
        }
    }
}

/// The serial ports the system knows, as (path, description).
pub fn list() -> io::Result<Vec<(String, String)>> {
    let ports = serialport::available_ports().map_err(io::Error::from)?;
    Ok(ports
        .into_iter()
        .map(|p| {
            let kind = match p.port_type {
                serialport::SerialPortType::UsbPort(u) => format!(
                    "USB {:04x}:{:04x} {}",
                    u.vid,
                    u.pid,
                    u.product.unwrap_or_default()
                ),
                serialport::SerialPortType::PciPort => "PCI".into(),
                serialport::SerialPortType::BluetoothPort => "Bluetooth".into(),
                serialport::SerialPortType::Unknown => String::new(),
            };
            (p.port_name, kind)
        })
        .collect())
}
