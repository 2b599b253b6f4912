//! What the HMI is showing ([`Page`]) and the per-page state the screens draw from.

use super::entry::{Form, FormKind};
use super::job::Job;
use super::text::Text;
use crate::keypad::Key;
use crate::motion::StepPos;

/// Jog page state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JogPage {
    /// The held direction key and its direction, while jogging.
    pub active: Option<(Key, [i8; 2])>,
    /// The latest direction (shown as the arrow).
    pub last_dir: [i8; 2],
}

/// The machine waits for the user (G-code's M0 or M6): drawn over any page until
/// cycle start; D continues.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PromptView {
    /// The pen to put in (M6 T`n`); `None`: a pause (M0).
    pub pen: Option<u8>,
    /// The last `(MSG, ...)` text.
    pub message: Text<PROMPT_MESSAGE>,
}

/// The message's room on the prompt: two lines of the LCD.
pub const PROMPT_MESSAGE: usize = 42;

/// Where a running job is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunPhase {
    /// Queued or moving (the machine state says whether held).
    Running,
    /// Abort sent; waiting for the machine to stop.
    Stopping,
    /// Finished after `ms`; `complete` = reached its end point.
    Done { ms: u32, complete: bool },
}

/// A job being drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunPage {
    pub job: Job,
    pub start: StepPos,
    pub end: StepPos,
    pub started_ms: u32,
    pub phase: RunPhase,
    /// Path covered so far (sum of position changes) and the job's length, in mm.
    pub traveled_mm: f32,
    pub length_mm: f32,
    pub(super) last_pos: StepPos,
    pub(super) idle_since: Option<u32>,
}

impl RunPage {
    /// Fraction done, 0..=1.
    pub fn progress(&self) -> f32 {
        match self.phase {
            RunPhase::Done { complete: true, .. } => 1.0,
            _ if self.length_mm > 0.0 => (self.traveled_mm / self.length_mm).clamp(0.0, 0.99),
            _ => 0.0,
        }
    }

    pub fn elapsed_ms(&self, now_ms: u32) -> u32 {
        match self.phase {
            RunPhase::Done { ms, .. } => ms,
            _ => now_ms.wrapping_sub(self.started_ms),
        }
    }
}

/// What is on the screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Page {
    Boot,
    Menu {
        sel: usize,
    },
    Machine {
        sel: usize,
    },
    Jog(JogPage),
    Form(Form),
    /// The curve preview before drawing; `form` is where Back returns.
    Preview {
        job: Job,
        form: Option<FormKind>,
    },
    Run(RunPage),
    Status,
    Alarm {
        code: u8,
    },
    /// A refused command: one of the HMI's fixed messages.
    Error {
        title: &'static str,
        text: &'static str,
    },
}

/// A short message on the bottom line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Toast {
    pub text: Text<28>,
    pub(super) until_ms: u32,
}

/// Feed directions remembered for the teaching view.
pub const DIR_HISTORY: usize = 6;
