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

/// The main menu's lines as shown: " hotkey label", in [`MENU`] order.
pub const MENU_LINES: [&str; 10] = [
    " 1 Jog (manual)",
    " 2 Line",
    " 3 Arc / circle",
    " 4 Ellipse",
    " 5 Sine curve",
    " 6 Star",
    " 7 Pen up/down",
    " 8 Replay last",
    " 9 Machine...",
    " 0 Status/setup",
];

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

/// The machine submenu's lines as shown, in [`MACHINE_MENU`] order.
pub const MACHINE_LINES: [&str; 3] = [" 1 Go to origin", " 2 Set origin here", " 3 Homing cycle"];

#[cfg(test)]
mod tests {
    use super::*;

    /// Each shown line starts with its entry's hotkey.
    #[test]
    fn lines_show_the_hotkeys() {
        let main = MENU.iter().map(|e| e.0).zip(MENU_LINES);
        let machine = MACHINE_MENU.iter().map(|e| e.0).zip(MACHINE_LINES);
        for (key, line) in main.chain(machine) {
            assert!(
                line.as_bytes().starts_with(&[b' ', b'0' + key, b' ']),
                "{line}"
            );
            assert!(line.len() > 4);
        }
    }

    /// What the state machine computes instead of searching the tables: hotkey d is
    /// entry (d + 9) % 10, and the drawing modes follow Jog in form order.
    #[test]
    fn hotkeys_and_draw_entries_are_in_order() {
        for (i, (key, _)) in MENU.iter().enumerate() {
            assert_eq!((usize::from(*key) + 9) % 10, i);
        }
        for (i, (key, _)) in MACHINE_MENU.iter().enumerate() {
            assert_eq!((usize::from(*key) + 9) % 10, i);
        }
        for kind in crate::hmi::entry::FORM_KINDS {
            assert_eq!(MENU[kind.index() + 1].1, MenuItem::Draw(kind));
        }
    }
}
