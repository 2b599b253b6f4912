//! Random key and machine-state sequences through the HMI and the screens: nothing
//! panics, no response is ever truncated by the fixed-size action list, every queued
//! move stays inside the step range, and the incrementally painted frame buffer always
//! equals a from-scratch render (no stale pixels from painting in place).

use inkstep_core::hmi::{Action, Actions, Config, Hmi, MachineState, Page, Snapshot};
use inkstep_core::keypad::{KeyEvent, KeyKind, KEYMAP};
use inkstep_core::screens::framebuffer::FrameBuffer;
use inkstep_core::screens::Screens;
use proptest::prelude::*;

fn state(i: u8) -> MachineState {
    match i {
        0..=3 => MachineState::Idle,
        4 => MachineState::Run,
        5 => MachineState::Hold,
        6 => MachineState::Jog,
        7 => MachineState::Homing,
        _ => MachineState::Alarm(i - 7),
    }
}

fn check(a: &Actions) -> Result<(), TestCaseError> {
    prop_assert!(a.len() < a.capacity(), "action list full: {a:?}");
    for act in a {
        if let Action::Queue(m) = act {
            prop_assert!(m.target.iter().all(|v| v.unsigned_abs() < 1_000_000_000));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn random_sessions_never_panic_or_truncate(
        ops in proptest::collection::vec(
            (0usize..16, 0u8..3, 0u8..12, -40_000i32..40_000, -40_000i32..40_000, any::<bool>()),
            0..300,
        )
    ) {
        let mut hmi = Hmi::new(Config::default(), 0);
        let mut screens = Screens::new();
        let mut fb = FrameBuffer::new();
        let mut now = 0u32;
        for (k, kind, s, x, y, empty) in ops {
            now = now.wrapping_add(37);
            let st = Snapshot {
                state: state(s),
                pos: [x, y, if empty { 0 } else { 500 }],
                feed_mm_min: 300.0,
                queue_empty: empty,
                dir: [(x.rem_euclid(3) - 1) as i8, (y.rem_euclid(3) - 1) as i8],
            };
            let key = KEYMAP[k / 4][k % 4];
            let kind = [KeyKind::Press, KeyKind::Repeat, KeyKind::Release][kind as usize];
            check(&hmi.key(KeyEvent { key, kind }, &st, now))?;
            check(&hmi.tick(&st, now))?;
            screens.render(&hmi, &st, now, &mut fb).unwrap();
            // The drawing page's trace may be decimated, so a rebuild is only close.
            if !matches!(hmi.page(), Page::Run(_)) {
                let mut again = screens.clone();
                again.invalidate();
                let mut fresh = FrameBuffer::new();
                again.render(&hmi, &st, now, &mut fresh).unwrap();
                prop_assert!(fresh.bytes() == fb.bytes(), "stale pixels on {:?}", hmi.page());
            }
        }
    }
}
