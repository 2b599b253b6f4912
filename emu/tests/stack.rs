//! The image's handlers run on an 8-byte aligned stack. The compiler assumes the
//! AAPCS alignment in every function (it forms the address of a stack slot with ORR
//! where that is the same as ADD), but the STM32F103's Cortex-M3 r1p1 resets with
//! CCR.STKALIGN clear: an interrupt taken while SP is 4 mod 8 then runs its task on a
//! misaligned stack, which once made the preparation task trace an arc the wrong way
//! round (emu/random-regressions/seed-268613718.nc). The image sets STKALIGN in init;
//! this runs a job that keeps every task busy (arcs streamed with character counting,
//! `?` every 10 ms, the LCD drawing) and counts the handler entries on a misaligned
//! stack.

mod common;

use common::booted;
use inkstep_emu::clock::{T_PER_MS, T_PER_S};
use inkstep_serial::sender::Flow;

#[test]
fn every_handler_starts_on_an_8_byte_aligned_stack_during_a_busy_job() {
    let mut s = booted(None);
    let job = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../bench/arcs-ij.nc"),
    )
    .unwrap();
    let mut next_query = s.now();
    let got = s
        .stream(&job, Flow::CharCount(128), 120 * T_PER_S, |s| {
            if s.now() >= next_query {
                s.send(b"?");
                next_query = s.now() + 10 * T_PER_MS;
            }
            Ok(())
        })
        .expect("stream");
    assert!(got.errors.is_empty() && got.alarms.is_empty(), "{got:?}");
    s.wait_idle(60 * T_PER_S).expect("idle");
    let p = s.m.state_mut().profile_now();
    let entries: u64 = p.entries.iter().sum();
    assert!(entries > 10_000, "{entries} handler entries");
    assert_eq!(
        p.misaligned_entries, 0,
        "{} of {entries} handler entries on a stack at 4 mod 8",
        p.misaligned_entries
    );
}
