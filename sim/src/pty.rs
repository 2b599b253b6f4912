//! A pseudo-terminal that stands in for the board's USB CDC-ACM serial port.
//!
//! Owns only the operating-system side: open the pair, put the line in raw mode (no
//! echo, no line editing, 8-bit clean, like CDC-ACM), symlink it where senders expect a
//! port, and move bytes without blocking. The simulator keeps its own handle on the
//! client side open so that clients can come and go without the master seeing EIO.

use rustix::fs::{fcntl_getfl, fcntl_setfl, OFlags};
use rustix::pty::{grantpt, openpt, ptsname, unlockpt, OpenptFlags};
use rustix::termios::{tcgetattr, tcsetattr, OptionalActions};
use std::fs::File;
use std::io::{self, Read, Write};
use std::os::fd::OwnedFd;
use std::path::{Path, PathBuf};

pub struct Pty {
    master: File,
    _client_keepalive: File,
    path: PathBuf,
    link: Option<PathBuf>,
    pending: Vec<u8>,
}

impl Pty {
    /// Opens a new pseudo-terminal in raw mode.
    pub fn open() -> io::Result<Pty> {
        let master: OwnedFd = openpt(OpenptFlags::RDWR | OpenptFlags::NOCTTY)?;
        grantpt(&master)?;
        unlockpt(&master)?;
        let name = ptsname(&master, Vec::new())?;
        let path = PathBuf::from(name.to_string_lossy().into_owned());
        let client = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)?;
        let mut t = tcgetattr(&client)?;
        t.make_raw();
        tcsetattr(&client, OptionalActions::Now, &t)?;
        let flags = fcntl_getfl(&master)?;
        fcntl_setfl(&master, flags | OFlags::NONBLOCK)?;
        Ok(Pty {
            master: File::from(master),
            _client_keepalive: client,
            path,
            link: None,
            pending: Vec::new(),
        })
    }

    /// The client-side device path (e.g. /dev/pts/3).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Makes `link` a symlink to the device, replacing an old symlink there.
    pub fn link_at(&mut self, link: &Path) -> io::Result<()> {
        if let Ok(m) = std::fs::symlink_metadata(link) {
            if m.file_type().is_symlink() {
                std::fs::remove_file(link)?;
            }
        }
        std::os::unix::fs::symlink(&self.path, link)?;
        self.link = Some(link.to_path_buf());
        Ok(())
    }

    /// Reads what the client has sent so far; 0 when nothing is waiting.
    pub fn read_available(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self.master.read(buf) {
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(0),
            // EIO: no client has the port open right now.
            Err(e) if e.raw_os_error() == Some(5) => Ok(0),
            Err(e) => Err(e),
        }
    }

    /// Queues bytes for the client and sends as many as it takes now.
    pub fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.pending.extend_from_slice(bytes);
        self.flush_pending()
    }

    /// Sends queued bytes without blocking; returns with the rest still queued.
    pub fn flush_pending(&mut self) -> io::Result<()> {
        while !self.pending.is_empty() {
            match self.master.write(&self.pending) {
                Ok(0) => break,
                Ok(n) => {
                    self.pending.drain(..n);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(e) if e.raw_os_error() == Some(5) => break,
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

impl Drop for Pty {
    fn drop(&mut self) {
        if let Some(l) = &self.link {
            let _ = std::fs::remove_file(l);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_cross_both_ways_raw() {
        let mut pty = Pty::open().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("ttyINKSTEP");
        pty.link_at(&link).unwrap();
        let mut client = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&link)
            .unwrap();
        // A real-time byte without a newline and a control byte must arrive as they are.
        client.write_all(b"?\x18G0 X1\n").unwrap();
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        for _ in 0..100 {
            let n = pty.read_available(&mut buf).unwrap();
            got.extend_from_slice(&buf[..n]);
            if got.len() >= 8 {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert_eq!(got, b"?\x18G0 X1\n");
        pty.send(b"ok\r\n").unwrap();
        let mut back = [0u8; 4];
        client.read_exact(&mut back).unwrap();
        assert_eq!(&back, b"ok\r\n");
        drop(pty);
        assert!(
            std::fs::symlink_metadata(&link).is_err(),
            "link removed on drop"
        );
    }
}
