//! G-code modal groups: the modal state a block changes (motion mode, units, distance
//! and feed modes, coordinate system, pen) and the tables that sort a block's G and M
//! codes into their groups, so that a group named twice is refused (error 21) before
//! the interpreter acts on anything.

use super::parser::Code;
use super::ErrorCode;

/// Motion mode (modal group 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionMode {
    Rapid,
    Linear,
    ArcCw,
    ArcCcw,
    Cancel,
}

/// The modal state reported by `$G`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Modal {
    pub motion: MotionMode,
    pub inches: bool,
    pub incremental: bool,
    pub inverse_time: bool,
    /// Active work coordinate system, 0 = G54 .. 5 = G59.
    pub wcs: u8,
    pub pen_down: bool,
    /// The pen level queued last (0 = up .. `motion::PEN_FULL` = down): `M3` with
    /// `S` sets it within $31..$30.
    pub pen_level: u16,
    /// G43.1 (dynamic tool length offset) in effect; G49 (the default) cancels it.
    pub tool_length: bool,
}

impl Modal {
    /// The state at power-on and after a soft reset: G0 G54 G21 G90 G94 G49, pen up.
    pub const INITIAL: Modal = Modal {
        motion: MotionMode::Rapid,
        inches: false,
        incremental: false,
        inverse_time: false,
        wcs: 0,
        pen_down: false,
        pen_level: 0,
        tool_length: false,
    };
}

impl Default for Modal {
    fn default() -> Self {
        Modal::INITIAL
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum NonModal {
    Dwell,
    SetCoord,
    Home28,
    Set28,
    Home30,
    Set30,
    Absolute,
    SetG92,
    ResetG92,
}

pub(super) const MOTION_MODES: [MotionMode; 5] = [
    MotionMode::Rapid,
    MotionMode::Linear,
    MotionMode::ArcCw,
    MotionMode::ArcCcw,
    MotionMode::Cancel,
];
pub(super) const NON_MODAL: [NonModal; 9] = [
    NonModal::Dwell,
    NonModal::SetCoord,
    NonModal::Home28,
    NonModal::Set28,
    NonModal::Home30,
    NonModal::Set30,
    NonModal::Absolute,
    NonModal::SetG92,
    NonModal::ResetG92,
];
// Modal groups of the G codes; the plane, arc distance, cutter compensation and path
// mode groups are accepted (only their default exists) and checked for repeats.
// Groups 0-10 are the G groups (motion, non-modal, units, distance, feed mode,
// coordinate system, then the accepted defaults); 11-15 the M groups (stop, M1, pen,
// coolant, tool change). A group not named in the block holds NONE.
pub(super) const GROUPS: usize = 16;
pub(super) const NONE: u8 = u8::MAX;
/// G code (x10), its group and its value in the group (an index into MOTION_MODES
/// or NON_MODAL; 1 = inches / incremental / inverse time / G43.1; the coordinate
/// system).
pub(super) const G_CODES: [(u16, u8, u8); 32] = [
    (0, 0, 0),
    (10, 0, 1),
    (20, 0, 2),
    (30, 0, 3),
    (800, 0, 4),
    (40, 1, 0),
    (100, 1, 1),
    (280, 1, 2),
    (281, 1, 3),
    (300, 1, 4),
    (301, 1, 5),
    (530, 1, 6),
    (920, 1, 7),
    (921, 1, 8),
    (200, 2, 1),
    (210, 2, 0),
    (900, 3, 0),
    (910, 3, 1),
    (930, 4, 1),
    (940, 4, 0),
    (540, 5, 0),
    (550, 5, 1),
    (560, 5, 2),
    (570, 5, 3),
    (580, 5, 4),
    (590, 5, 5),
    (170, 6, 0),
    (911, 7, 0),
    (400, 8, 0),
    (431, 9, 1),
    (490, 9, 0),
    (610, 10, 0),
];
/// M codes in the same form: stop 0 = M0, 1 = M2/M30; M1; pen 1 = down (M3/M4),
/// 0 = up (M5); coolant (accepted, nothing to switch); M6, the manual pen change.
pub(super) const M_CODES: [(u16, u8, u8); 11] = [
    (0, 11, 0),
    (20, 11, 1),
    (300, 11, 1),
    (10, 12, 0),
    (30, 13, 1),
    (40, 13, 1),
    (50, 13, 0),
    (70, 14, 0),
    (80, 14, 0),
    (90, 14, 0),
    (60, 15, 0),
];

/// Put each code's value into its group; a group named twice is error 21, an unknown
/// code the error Grbl gives for it.
pub(super) fn group_codes(
    codes: &[Code],
    table: &[(u16, u8, u8)],
    groups: &mut [u8; GROUPS],
    g: bool,
) -> Result<(), ErrorCode> {
    for &code in codes {
        let Some(&(_, group, value)) = table.iter().find(|e| e.0 == code) else {
            // G59.1-G59.3 included: Grbl reads them as G59 with a fraction (error 23),
            // never reaching its unsupported-coordinate-system check.
            return Err(
                if code % 10 != 0 && !(g && matches!(code / 10, 18 | 19 | 38 | 43 | 90 | 61)) {
                    ErrorCode::CommandValueNotInteger
                } else {
                    ErrorCode::UnsupportedCommand
                },
            );
        };
        if let Some(slot) = groups.get_mut(usize::from(group)) {
            if *slot != NONE {
                return Err(ErrorCode::ModalGroupViolation);
            }
            *slot = value;
        }
    }
    Ok(())
}
