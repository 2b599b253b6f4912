//! The byte stream into the protocol: real-time bytes acted on at once (they never
//! take buffer space), the 128-byte receive buffer senders count characters against
//! (flow control: a full buffer stops `receive`, back-pressure toward the host), and
//! the framing of lines (CR, LF or CR LF end a line; the cleaner strips spaces and
//! comments).

use super::{Protocol, OUT_RESERVE, RX_BUFFER_SIZE, STATUS_PENDING_MAX};
use crate::machine::MotionControl;

/// Whether `b` is a real-time command: acted on when it arrives, never part of a line
/// (`?`, `!`, `~`, Ctrl-X and every byte from 0x80). The shell's USB task hands a
/// packet holding one to the protocol at once ([`crate::controller::Controller::take_realtime`]).
pub fn is_realtime(b: u8) -> bool {
    matches!(b, b'?' | b'!' | b'~' | 0x18 | 0x80..=0xFF)
}

impl Protocol {
    /// Free bytes in the receive buffer (what `Bf:` reports).
    pub fn rx_free(&self) -> usize {
        RX_BUFFER_SIZE - self.rx.len()
    }

    /// One received byte: a real-time command acts at once, any other byte goes into
    /// the receive buffer. False if the buffer is full: the byte was not taken and must
    /// be offered again later (back-pressure).
    pub fn take_byte<M: MotionControl>(&mut self, b: u8, m: &mut M, now_ms: u32) -> bool {
        self.realtime(b, m, now_ms) || self.rx.push_back(b).is_ok()
    }

    /// Handle `b` if it is a real-time command ([`is_realtime`]).
    fn realtime<M: MotionControl>(&mut self, b: u8, m: &mut M, now_ms: u32) -> bool {
        match b {
            // Every `?` gets its own report: now, or as soon as the output buffer has
            // room (Grbl drops a `?` that comes before the last one was answered).
            b'?' => {
                // In order: behind a reset's welcome or other reports still waiting.
                if self.room() >= OUT_RESERVE && !self.welcome_due && self.status_requested == 0 {
                    self.status_report(m);
                } else if self.status_requested < STATUS_PENDING_MAX {
                    self.status_requested += 1;
                }
            }
            b'!' => self.machine.feed_hold(m),
            b'~' => self.machine.cycle_start(m),
            0x18 => self.soft_reset(m),
            0x84 => self.machine.safety_door(m),
            0x85 => self.machine.jog_cancel(m),
            0x90..=0x97 => self.machine.override_command(b, m),
            // Other extended real-time bytes (door, spindle and coolant overrides)
            // have no meaning on a plotter; never let them into a line.
            0x80..=0xFF => {}
            _ => return false,
        }
        let _ = now_ms;
        true
    }

    fn soft_reset<M: MotionControl>(&mut self, m: &mut M) {
        self.machine.soft_reset(m);
        self.rx.clear();
        self.line.clear();
        self.cleaner.reset();
        self.line_too_long = false;
        self.line_ready = false;
        self.ok_when_idle = false;
        self.after_cr = false;
        self.listing = None;
        self.startup_next = Some(0);
        // The welcome (and the reset's alarm) as soon as the output has room for them
        // whole: a flood of resets says it once and cuts no line.
        self.welcome_due = true;
        if self.room() >= OUT_RESERVE {
            self.welcome_due = false;
            self.flush_events();
            self.welcome();
        }
    }

    /// Move bytes from the receive buffer into the line; true when a line is complete.
    pub(super) fn frame_line(&mut self) -> bool {
        while let Some(b) = self.rx.pop_front() {
            let lf_after_cr = b == b'\n' && self.after_cr;
            self.after_cr = b == b'\r';
            if lf_after_cr {
                continue;
            }
            if b == b'\n' || b == b'\r' {
                self.cleaner.reset();
                self.line_ready = true;
                return true;
            }
            let in_comment = self.cleaner.in_comment();
            if let Some(c) = self.cleaner.push(b) {
                if self.line.push(c).is_err() {
                    self.line_too_long = true;
                }
            }
            // The first `(...)` comment's text, for `(MSG, ...)`.
            if in_comment && !self.comment_done {
                if self.cleaner.in_comment() {
                    let _ = self.comment.push(b);
                } else {
                    self.comment_done = true;
                }
            }
        }
        false
    }

    pub(super) fn finish_frame(&mut self) {
        self.comment.clear();
        self.comment_done = false;
        self.line.clear();
        self.line_too_long = false;
        self.line_ready = false;
    }
}
