//! The menus: which entries exist, their hotkeys and labels. Data only; the state
//! machine in [`super::Hmi`] decides what opening an entry does.

use super::entry::FormKind;

/// Main menu entries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MenuItem {
    Jog,
    Draw(FormKind),
    Pen,
    Replay,
    Machine,
    Status,
}

/// The main menu: (hotkey digit, entry).
pub const MENU: [(u8, MenuItem); 10] = [
    (1, MenuItem::Jog),
    (2, MenuItem::Draw(FormKind::Line)),
    (3, MenuItem::Draw(FormKind::Arc)),
    (4, MenuItem::Draw(FormKind::Ellipse)),
    (5, MenuItem::Draw(FormKind::Sine)),
    (6, MenuItem::Draw(FormKind::Star)),
    (7, MenuItem::Pen),
    (8, MenuItem::Replay),
    (9, MenuItem::Machine),
    (0, MenuItem::Status),
];

impl MenuItem {
    pub fn label(self) -> &'static str {
        match self {
            MenuItem::Jog => "Jog (manual)",
            MenuItem::Draw(FormKind::Line) => "Line",
            MenuItem::Draw(FormKind::Arc) => "Arc / circle",
            MenuItem::Draw(FormKind::Ellipse) => "Ellipse",
            MenuItem::Draw(FormKind::Sine) => "Sine curve",
            MenuItem::Draw(FormKind::Star) => "Star",
            MenuItem::Pen => "Pen up/down",
            MenuItem::Replay => "Replay last",
            MenuItem::Machine => "Machine...",
            MenuItem::Status => "Status/setup",
        }
    }
}

/// The machine submenu.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MachineItem {
    GoOrigin,
    SetOrigin,
    Home,
}

pub const MACHINE_MENU: [(u8, MachineItem); 3] = [
    (1, MachineItem::GoOrigin),
    (2, MachineItem::SetOrigin),
    (3, MachineItem::Home),
];

impl MachineItem {
    pub fn label(self) -> &'static str {
        match self {
            MachineItem::GoOrigin => "Go to origin",
            MachineItem::SetOrigin => "Set origin here",
            MachineItem::Home => "Homing cycle",
        }
    }
}
