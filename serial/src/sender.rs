//! The one Grbl sender: which line goes next and which line an answer belongs to.
//!
//! Grbl answers every line with exactly one `ok` or `error:N`, in order. With
//! send-response one line is in flight at a time; with character counting the sender
//! keeps the bytes of the lines sent but not yet answered (newline included) within
//! the controller's receive buffer, so it never overflows and the planner never
//! starves. Real-time bytes (`?`, `!`, `~`, 0x18, overrides) bypass the buffer and are
//! the caller's business.
//!
//! This is the protocol logic only, without I/O or a clock, so the simulator drives it
//! in virtual time and the host tool's drivers (the `send` stream, the web view's link)
//! in wall-clock time. Each line carries a tag of the caller's choice (its line in a
//! file, or who asked for it), returned with its answer.

use crate::grbl::{parse_reply, Reply};
use std::collections::VecDeque;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Send a line, wait for its answer.
    SendResponse,
    /// Keep up to this many bytes unanswered in the controller's receive buffer.
    CharCount(usize),
}

/// How the controller answered a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    Ok,
    Error(u32),
}

/// What the controller said, with answers matched to their lines.
#[derive(Clone, Debug, PartialEq)]
pub enum Event<T> {
    /// The answer to the line tagged `T`.
    Answered(T, Answer),
    /// Anything else (status, alarm, feedback, settings, welcome, or an answer with
    /// no line in flight).
    Reply(Reply),
}

pub struct Sender<T> {
    flow: Flow,
    /// Lines not yet sent.
    queue: VecDeque<(T, String)>,
    /// Lines sent and not yet answered, with their byte counts.
    in_flight: VecDeque<(T, usize)>,
    used: usize,
    partial: Vec<u8>,
}

impl<T: Clone> Sender<T> {
    pub fn new(flow: Flow) -> Self {
        Sender {
            flow,
            queue: VecDeque::new(),
            in_flight: VecDeque::new(),
            used: 0,
            partial: Vec::new(),
        }
    }

    pub fn flow(&self) -> Flow {
        self.flow
    }

    /// Changes the flow control (e.g. to the buffer size the controller advertises).
    pub fn set_flow(&mut self, flow: Flow) {
        self.flow = flow;
    }

    /// Queues a line (without its newline).
    pub fn push(&mut self, tag: T, line: impl Into<String>) {
        self.queue.push_back((tag, line.into()));
    }

    /// The bytes that may be sent now (possibly none). A line longer than the whole
    /// buffer goes alone, once nothing else is in flight.
    pub fn to_send(&mut self) -> Vec<u8> {
        let mut out = Vec::new();
        while let Some((_, text)) = self.queue.front() {
            let len = text.len() + 1;
            let allowed = self.in_flight.is_empty()
                || match self.flow {
                    Flow::SendResponse => false,
                    Flow::CharCount(cap) => self.used + len <= cap,
                };
            if !allowed {
                break;
            }
            let Some((tag, text)) = self.queue.pop_front() else {
                break;
            };
            out.extend_from_slice(text.as_bytes());
            out.push(b'\n');
            self.in_flight.push_back((tag, len));
            self.used += len;
        }
        out
    }

    /// Feeds bytes the controller sent; returns what they said, line by line.
    pub fn received(&mut self, bytes: &[u8]) -> Vec<Event<T>> {
        let mut out = Vec::new();
        for &b in bytes {
            if b != b'\n' {
                self.partial.push(b);
                continue;
            }
            let line = String::from_utf8_lossy(&self.partial).trim().to_string();
            self.partial.clear();
            if line.is_empty() {
                continue;
            }
            let reply = parse_reply(&line);
            let answer = match reply {
                Reply::Ok => Some(Answer::Ok),
                Reply::Error(n) => Some(Answer::Error(n)),
                _ => None,
            };
            match (answer, self.in_flight.pop_front()) {
                (Some(a), Some((tag, n))) => {
                    self.used -= n;
                    out.push(Event::Answered(tag, a));
                }
                (None, Some(f)) => {
                    self.in_flight.push_front(f);
                    out.push(Event::Reply(reply));
                }
                (_, None) => out.push(Event::Reply(reply)),
            }
        }
        out
    }

    /// Forgets every queued and unanswered line: after a soft reset or a restart the
    /// controller has dropped its receive buffer, and those lines get no answer.
    pub fn clear(&mut self) {
        self.queue.clear();
        self.in_flight.clear();
        self.used = 0;
    }

    /// Drops the lines not yet sent (the ones in flight still get their answers).
    pub fn drop_queued(&mut self) {
        self.queue.clear();
    }

    /// The oldest line sent and not yet answered.
    pub fn oldest_in_flight(&self) -> Option<&T> {
        self.in_flight.front().map(|f| &f.0)
    }

    /// Lines waiting to be sent.
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// Lines sent and not yet answered.
    pub fn in_flight(&self) -> usize {
        self.in_flight.len()
    }

    /// Every line has been sent and answered.
    pub fn done(&self) -> bool {
        self.queue.is_empty() && self.in_flight.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sender(text: &str, flow: Flow) -> Sender<usize> {
        let mut s = Sender::new(flow);
        for (i, l) in text.lines().enumerate() {
            s.push(i + 1, l);
        }
        s
    }

    #[test]
    fn send_response_keeps_one_line_in_flight() {
        let mut s = sender("G1 X1\nG1 Y1\n", Flow::SendResponse);
        assert_eq!(s.to_send(), b"G1 X1\n");
        assert!(s.to_send().is_empty());
        assert_eq!(s.received(b"o"), []);
        assert!(s.to_send().is_empty());
        assert_eq!(s.received(b"k\r\n"), [Event::Answered(1, Answer::Ok)]);
        assert_eq!(s.to_send(), b"G1 Y1\n");
        assert_eq!(
            s.received(b"error:20\r\n"),
            [Event::Answered(2, Answer::Error(20))]
        );
        assert!(s.done());
    }

    #[test]
    fn character_counting_fills_the_buffer() {
        // Lines of 10 bytes with the newline; 25 bytes of room: two lines at a time.
        let mut s = sender("G1 X1.000\nG1 X2.000\nG1 X3.000\n", Flow::CharCount(25));
        assert_eq!(s.to_send().len(), 20);
        assert_eq!(s.oldest_in_flight(), Some(&1));
        let ev = s.received(b"ok\r\n<Idle|MPos:0,0,0>\r\n[MSG:Job started]\r\n");
        assert_eq!(ev.len(), 3);
        assert_eq!(ev[0], Event::Answered(1, Answer::Ok));
        assert!(matches!(&ev[1], Event::Reply(Reply::Status(st)) if st.state == "Idle"));
        assert_eq!(s.to_send().len(), 10);
        let ev = s.received(b"ALARM:2\r\nok\r\nok\r\nok\r\n");
        assert_eq!(
            ev,
            [
                Event::Reply(Reply::Alarm(2)),
                Event::Answered(2, Answer::Ok),
                Event::Answered(3, Answer::Ok),
                Event::Reply(Reply::Ok),
            ]
        );
        assert!(s.done());
    }

    #[test]
    fn an_oversized_line_goes_alone_and_clear_forgets_everything() {
        let mut s = sender("G1 X1\nG1 X2 Y3 Z4\nG1 X3\n", Flow::CharCount(8));
        assert_eq!(s.to_send(), b"G1 X1\n");
        s.received(b"ok\n");
        assert_eq!(s.to_send(), b"G1 X2 Y3 Z4\n");
        assert!(s.to_send().is_empty());
        s.clear();
        assert!(s.done());
        assert!(s.to_send().is_empty());
        assert_eq!(s.received(b"ok\n"), [Event::Reply(Reply::Ok)]);
    }
}
