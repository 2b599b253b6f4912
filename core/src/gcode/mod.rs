//! G-code: the line cleaner and word parser ([`parser`]), the modal groups
//! ([`modal`]), the interpreter ([`interpreter`]) that turns blocks into queued motion
//! in steps, the arc geometry of G2/G3 (`arcs`), and millimetres to steps with the
//! travel limits ([`units`]).
//!
//! Errors use Grbl 1.1's status numbers ([`ErrorCode`]) so that senders show the right
//! message; they are shared with the `$` commands of the protocol.

mod arcs;
pub mod interpreter;
pub mod modal;
pub mod parser;
pub mod units;

pub use interpreter::{Interpreter, Outcome, Reject, Stop};
pub use parser::{LineCleaner, WordBlock};

/// Longest line after cleaning (Grbl's limit); longer lines get `error:11`.
pub const LINE_MAX: usize = 80;
/// Number of `$N` startup lines: G-code lines kept in flash and run after each reset.
pub const STARTUP_LINES: usize = 2;
/// A startup line as stored.
pub type StartupLine = heapless::String<LINE_MAX>;

/// `text` as a startup line; None unless it is ASCII (cleaned G-code is) and at most
/// [`LINE_MAX`] bytes. The one way in for the `$N` command, the store and boot; built
/// byte by byte, with no UTF-8 validation in the image.
pub fn startup_line(text: &[u8]) -> Option<StartupLine> {
    let mut line = StartupLine::new();
    for &b in text {
        // A one-byte char for ASCII; the sign bit makes the whole line unusable.
        if b >= 0x80 || line.push(char::from(b)).is_err() {
            return None;
        }
    }
    Some(line)
}

/// Grbl 1.1 status codes, sent as `error:N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum ErrorCode {
    ExpectedCommandLetter = 1,
    BadNumberFormat = 2,
    InvalidStatement = 3,
    NegativeValue = 4,
    HomingDisabled = 5,
    StepPulseMin = 6,
    SettingReadFail = 7,
    IdleError = 8,
    SystemLocked = 9,
    SoftLimitError = 10,
    Overflow = 11,
    MaxStepRateExceeded = 12,
    CheckDoor = 13,
    LineLengthExceeded = 14,
    TravelExceeded = 15,
    InvalidJogCommand = 16,
    UnsupportedCommand = 20,
    ModalGroupViolation = 21,
    UndefinedFeedRate = 22,
    CommandValueNotInteger = 23,
    AxisCommandConflict = 24,
    WordRepeated = 25,
    NoAxisWords = 26,
    InvalidLineNumber = 27,
    ValueWordMissing = 28,
    UnsupportedCoordSys = 29,
    G53InvalidMotionMode = 30,
    AxisWordsExist = 31,
    NoAxisWordsInPlane = 32,
    InvalidTarget = 33,
    ArcRadiusError = 34,
    NoOffsetsInPlane = 35,
    UnusedWords = 36,
    G43DynamicAxisError = 37,
    MaxValueExceeded = 38,
}

impl ErrorCode {
    /// The number sent after `error:`.
    pub fn code(self) -> u8 {
        self as u8
    }
}

impl From<crate::settings::SettingError> for ErrorCode {
    fn from(e: crate::settings::SettingError) -> Self {
        use crate::settings::SettingError as E;
        match e {
            E::Invalid => ErrorCode::InvalidStatement,
            E::Negative => ErrorCode::NegativeValue,
            E::PulseTooShort => ErrorCode::StepPulseMin,
            E::SoftLimitsNeedHoming => ErrorCode::SoftLimitError,
            E::StepRateTooHigh => ErrorCode::MaxStepRateExceeded,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn startup_lines_are_ascii_and_fit() {
        assert_eq!(startup_line(b"G21G90").as_deref(), Some("G21G90"));
        assert_eq!(startup_line(b"").as_deref(), Some(""));
        assert_eq!(startup_line(b"G0X\xc3\xa9"), None);
        let longest = [b'X'; LINE_MAX];
        assert_eq!(startup_line(&longest).map(|l| l.len()), Some(LINE_MAX));
        assert_eq!(startup_line(&[b'X'; LINE_MAX + 1]), None);
    }
}
