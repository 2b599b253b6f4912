//! The PC side of a stream: a G-code sender following Grbl's documented flow control,
//! as `cargo sim run` uses it against the simulated board.
//!
//! Owns only what a sender does: which line goes next (send-response: one line in
//! flight; character counting: as many as fit the advertised receive buffer), matching
//! each `ok` / `error:N` to its line, and noting alarms and messages. It knows nothing
//! about the board beyond the bytes.

use std::collections::VecDeque;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Send a line, wait for its answer.
    SendResponse,
    /// Keep up to this many bytes unanswered in the board's receive buffer.
    CharCount(usize),
}

/// A line that was answered with an error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// 1-based line number in the file.
    pub line_no: usize,
    pub text: String,
    pub response: String,
}

pub struct Sender {
    lines: Vec<String>,
    flow: Flow,
    next: usize,
    /// Indices of lines sent and not yet answered, with their byte counts.
    in_flight: VecDeque<(usize, usize)>,
    partial: Vec<u8>,
    pub errors: Vec<LineError>,
    pub alarms: Vec<String>,
    pub messages: Vec<String>,
    pub answered: usize,
}

impl Sender {
    /// A stream of the file's lines (comments and blanks are sent as they are; the
    /// board answers them too, like Grbl).
    pub fn new(text: &str, flow: Flow) -> Sender {
        Sender {
            lines: text
                .lines()
                .map(|l| l.trim_end_matches('\r').to_string())
                .collect(),
            flow,
            next: 0,
            in_flight: VecDeque::new(),
            partial: Vec::new(),
            errors: Vec::new(),
            alarms: Vec::new(),
            messages: Vec::new(),
            answered: 0,
        }
    }

    pub fn total_lines(&self) -> usize {
        self.lines.len()
    }

    /// The bytes that may be sent now (possibly none).
    pub fn to_send(&mut self) -> Vec<u8> {
        let mut out = Vec::new();
        while self.next < self.lines.len() {
            let len = self.lines[self.next].len() + 1;
            let allowed = match self.flow {
                Flow::SendResponse => self.in_flight.is_empty(),
                Flow::CharCount(cap) => {
                    let used: usize = self.in_flight.iter().map(|&(_, n)| n).sum();
                    used + len <= cap || self.in_flight.is_empty()
                }
            };
            if !allowed {
                break;
            }
            out.extend_from_slice(self.lines[self.next].as_bytes());
            out.push(b'\n');
            self.in_flight.push_back((self.next, len));
            self.next += 1;
        }
        out
    }

    /// Feeds bytes the board sent.
    pub fn received(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if b == b'\n' {
                let line = String::from_utf8_lossy(&self.partial).trim().to_string();
                self.partial.clear();
                self.response_line(line);
            } else {
                self.partial.push(b);
            }
        }
    }

    fn response_line(&mut self, line: String) {
        if line == "ok" || line.starts_with("error:") {
            if let Some((i, _)) = self.in_flight.pop_front() {
                self.answered += 1;
                if line != "ok" {
                    self.errors.push(LineError {
                        line_no: i + 1,
                        text: self.lines[i].clone(),
                        response: line,
                    });
                }
            }
        } else if line.starts_with("ALARM:") {
            self.alarms.push(line);
        } else if line.starts_with("[MSG:") {
            self.messages.push(line);
        }
    }

    /// Every line has been sent and answered.
    pub fn done(&self) -> bool {
        self.next == self.lines.len() && self.in_flight.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn send_response_keeps_one_line_in_flight() {
        let mut s = Sender::new("G1 X1\nG1 Y1\n", Flow::SendResponse);
        assert_eq!(s.to_send(), b"G1 X1\n");
        assert!(s.to_send().is_empty());
        s.received(b"o");
        assert!(s.to_send().is_empty());
        s.received(b"k\r\n");
        assert_eq!(s.to_send(), b"G1 Y1\n");
        s.received(b"error:20\r\n");
        assert!(s.done());
        assert_eq!(
            s.errors,
            vec![LineError {
                line_no: 2,
                text: "G1 Y1".into(),
                response: "error:20".into()
            }]
        );
    }

    #[test]
    fn character_counting_fills_the_buffer() {
        // Lines of 10 bytes with the newline; 25 bytes of room: two lines at a time.
        let mut s = Sender::new("G1 X1.000\nG1 X2.000\nG1 X3.000\n", Flow::CharCount(25));
        assert_eq!(s.to_send().len(), 20);
        s.received(b"ok\r\n<Idle|MPos:0,0,0>\r\n[MSG:Job started]\r\n");
        assert_eq!(s.to_send().len(), 10);
        s.received(b"ALARM:2\r\nok\r\nok\r\n");
        assert!(s.done());
        assert_eq!(s.alarms, vec!["ALARM:2"]);
        assert_eq!(s.messages, vec!["[MSG:Job started]"]);
        assert_eq!(s.answered, 3);
    }
}
