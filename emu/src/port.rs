//! Who has the board's serial port open: the pty's device node watched with inotify
//! (each open and close of it, through any path or symlink, is an event). A CDC-ACM
//! port's DTR line is up while a program has the port open (the kernel's class
//! driver raises it on open and drops it on the last close), so the count of open
//! handles is DTR for the emulated host.

use rustix::fs::inotify::{self, CreateFlags, ReadFlags, WatchFlags};
use std::mem::MaybeUninit;
use std::os::fd::OwnedFd;
use std::path::Path;

pub struct OpenWatch {
    fd: OwnedFd,
    open: i64,
}

impl OpenWatch {
    /// Watch `device` (opened before this call do not count).
    pub fn new(device: &Path) -> std::io::Result<OpenWatch> {
        let fd = inotify::init(CreateFlags::NONBLOCK | CreateFlags::CLOEXEC)?;
        inotify::add_watch(
            &fd,
            device,
            WatchFlags::OPEN | WatchFlags::CLOSE_WRITE | WatchFlags::CLOSE_NOWRITE,
        )?;
        Ok(OpenWatch { fd, open: 0 })
    }

    /// Some program has the port open now.
    pub fn is_open(&mut self) -> bool {
        let mut buf = [MaybeUninit::<u8>::uninit(); 1024];
        let mut reader = inotify::Reader::new(&self.fd, &mut buf);
        while let Ok(ev) = reader.next() {
            let e = ev.events();
            if e.contains(ReadFlags::OPEN) {
                self.open += 1;
            }
            if e.intersects(ReadFlags::CLOSE_WRITE | ReadFlags::CLOSE_NOWRITE) {
                self.open = (self.open - 1).max(0);
            }
        }
        self.open > 0
    }
}
