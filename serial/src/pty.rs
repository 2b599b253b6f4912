//! The server side of a pseudo-terminal that stands in for the board's USB CDC-ACM
//! serial port (`cargo sim serve`, `cargo emu serve`), and a way for tests to get one.
//!
//! Owns only the operating-system side: open the pair, put the line in raw mode (no
//! echo, no line editing, 8-bit clean, like CDC-ACM), symlink it where senders expect a
//! port, move bytes without blocking, and notice when a client opens or closes the
//! port. The server keeps its own handle on the client side open so that clients can
//! come and go without the master seeing EIO; the comings and goings are read from
//! inotify open/close events on the device node (our own handle is opened before the
//! watch, so it is not counted). When the last client closes, what it left unread is
//! discarded, as a USB host that closed the port would never read it: the next client
//! does not get stale answers.

use rustix::fs::inotify::{self, CreateFlags, ReadFlags, WatchFlags};
use rustix::fs::{fcntl_getfl, fcntl_setfl, OFlags};
use rustix::pty::{grantpt, openpt, ptsname, unlockpt, OpenptFlags};
use rustix::termios::{tcflush, tcgetattr, tcsetattr, OptionalActions, QueueSelector};
use std::fs::File;
use std::io::{self, Read, Write};
use std::mem::MaybeUninit;
use std::os::fd::OwnedFd;
use std::path::{Path, PathBuf};

/// A client opened or closed the port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClientEvent {
    Opened,
    Closed,
}

pub struct Pty {
    master: File,
    client_keepalive: File,
    path: PathBuf,
    link: Option<PathBuf>,
    pending: Vec<u8>,
    /// inotify watch on the device node, when the system allows one.
    watch: Option<OwnedFd>,
    clients: usize,
}

impl Pty {
    /// Opens a new pseudo-terminal in raw mode.
    pub fn open() -> io::Result<Pty> {
        // Close-on-exec: a program started later (a sender under test) must
        // not inherit the master, or the port never hangs up when this side
        // goes away.
        let master: OwnedFd =
            openpt(OpenptFlags::RDWR | OpenptFlags::NOCTTY | OpenptFlags::CLOEXEC)?;
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
        // Without inotify (or on a system whose pty nodes give no events) the port
        // still works; it just never reports clients.
        let watch = inotify::init(CreateFlags::NONBLOCK | CreateFlags::CLOEXEC)
            .ok()
            .filter(|fd| {
                inotify::add_watch(fd, &path, WatchFlags::OPEN | WatchFlags::CLOSE).is_ok()
            });
        Ok(Pty {
            master: File::from(master),
            client_keepalive: client,
            path,
            link: None,
            pending: Vec::new(),
            watch,
            clients: 0,
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

    /// Waits until the client has sent something, at most `timeout`: true if bytes
    /// are waiting. A server that has nothing else to do sleeps here, so that a byte
    /// (a `?`) is read the moment it arrives rather than at the next tick.
    pub fn wait_readable(&self, timeout: std::time::Duration) -> io::Result<bool> {
        use rustix::event::{poll, PollFd, PollFlags, Timespec};
        let mut fds = [PollFd::new(&self.master, PollFlags::IN)];
        let timeout = Timespec {
            tv_sec: timeout.as_secs() as _,
            tv_nsec: timeout.subsec_nanos() as _,
        };
        match poll(&mut fds, Some(&timeout)) {
            Ok(n) => Ok(n > 0 && fds[0].revents().contains(PollFlags::IN)),
            Err(rustix::io::Errno::INTR) => Ok(false),
            Err(e) => Err(e.into()),
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

    /// Client opens and closes since the last call, in order. When the last client
    /// has closed, the bytes it left unread are dropped.
    pub fn client_events(&mut self) -> io::Result<Vec<ClientEvent>> {
        let mut out = Vec::new();
        let Some(fd) = &self.watch else {
            return Ok(out);
        };
        let mut buf = [MaybeUninit::<u8>::uninit(); 1024];
        let mut reader = inotify::Reader::new(fd, &mut buf);
        loop {
            match reader.next() {
                Ok(ev) => {
                    let f = ev.events();
                    if f.contains(ReadFlags::OPEN) {
                        out.push(ClientEvent::Opened);
                    }
                    if f.intersects(ReadFlags::CLOSE_WRITE | ReadFlags::CLOSE_NOWRITE) {
                        out.push(ClientEvent::Closed);
                    }
                }
                Err(e) if e == rustix::io::Errno::AGAIN => break,
                Err(e) if e == rustix::io::Errno::INTR => continue,
                Err(e) => return Err(e.into()),
            }
        }
        for e in &out {
            match e {
                ClientEvent::Opened => self.clients += 1,
                ClientEvent::Closed => {
                    self.clients = self.clients.saturating_sub(1);
                    if self.clients == 0 {
                        self.pending.clear();
                        tcflush(&self.client_keepalive, QueueSelector::IFlush)?;
                    }
                }
            }
        }
        Ok(out)
    }

    /// Clients that have the port open, as far as [`Pty::client_events`] has seen.
    pub fn clients(&self) -> usize {
        self.clients
    }

    /// Whether clients opening and closing the port are noticed at all (the system
    /// gave an inotify watch); if not, [`Pty::clients`] says nothing.
    pub fn notices_clients(&self) -> bool {
        self.watch.is_some()
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
    use std::time::{Duration, Instant};

    fn read_some(pty: &mut Pty, want: usize) -> Vec<u8> {
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        let end = Instant::now() + Duration::from_secs(2);
        while got.len() < want && Instant::now() < end {
            let n = pty.read_available(&mut buf).unwrap();
            got.extend_from_slice(&buf[..n]);
            std::thread::sleep(Duration::from_millis(2));
        }
        got
    }

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
        assert_eq!(read_some(&mut pty, 8), b"?\x18G0 X1\n");
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

    #[test]
    fn clients_coming_and_going_are_seen_and_stale_output_is_dropped() {
        let mut pty = Pty::open().unwrap();
        assert_eq!(pty.client_events().unwrap(), []);
        let path = pty.path().to_path_buf();
        let open = || {
            std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(&path)
                .unwrap()
        };
        let first = open();
        assert_eq!(pty.client_events().unwrap(), [ClientEvent::Opened]);
        assert_eq!(pty.clients(), 1);
        // Answers the first client never read are gone when it closes.
        pty.send(b"stale\r\n").unwrap();
        drop(first);
        assert_eq!(pty.client_events().unwrap(), [ClientEvent::Closed]);
        assert_eq!(pty.clients(), 0);
        let mut second = open();
        pty.client_events().unwrap();
        pty.send(b"ok\r\n").unwrap();
        let mut back = [0u8; 4];
        second.read_exact(&mut back).unwrap();
        assert_eq!(&back, b"ok\r\n");
    }
}
