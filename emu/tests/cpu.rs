//! The exception model and the watchdog against the ARMv7-M Architecture Reference
//! Manual and RM0008, with small hand-written programs (tests/programs/*.s, assembled
//! by tests/programs/build): each logs what it saw into RAM, the test reads it back.
//! The programs run at the reset clock (8 MHz HSI, no flash wait states): each
//! instruction costs its Cortex-M3 cycles, exception entry 12 cycles, return 12,
//! tail-chaining 6 (emu/README.md, "Cycle model").

use inkstep_emu::clock::{T_PER_MS, T_PER_S, T_PER_US};
use inkstep_emu::cpu_model::CpuModel;
use inkstep_emu::elf::Image;
use inkstep_emu::machine::{Machine, Stop};
use inkstep_emu::periph::flash::Flash;
use std::path::Path;

const LOG: u64 = 0x2000_0000;

fn load(name: &str) -> Machine<'static> {
    load_with(name, CpuModel::Pessimistic)
}

fn load_with(name: &str, model: CpuModel) -> Machine<'static> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/programs")
        .join(format!("{name}.elf"));
    let image = Image::read(&path).unwrap();
    let mut m = Machine::new(&image, Flash::new(None).unwrap()).unwrap();
    m.state_mut().model = model;
    m
}

/// Run until the program exits (status 0 expected); returns its log.
fn run(m: &mut Machine) -> Vec<u32> {
    match m.run_until(m.now() + T_PER_S) {
        Some(Stop::Exit(0)) => {}
        other => panic!("the program ended with {other:?}; log {:x?}", log(m)),
    }
    log(m)
}

fn word(m: &Machine, at: u64) -> u32 {
    let mut b = [0u8; 4];
    m.uc.mem_read(at, &mut b).unwrap();
    u32::from_le_bytes(b)
}

fn log(m: &Machine) -> Vec<u32> {
    let n = word(m, LOG);
    (1..=u64::from(n)).map(|i| word(m, LOG + 4 * i)).collect()
}

fn ch(c: char) -> u32 {
    c as u32
}

#[test]
fn a_more_urgent_interrupt_preempts_and_a_less_urgent_one_tail_chains() {
    // From IRQ0's last cycle count to IRQ2's first: str (2, or 1 pipelined behind the
    // ldr), pop {r4, r5, pc} to EXC_RETURN (1 + 3), the tail-chain (6), then IRQ2's
    // mov (1), ldr = (2), ldr (2, or 1 pipelined): 17 pessimistic, 15 typical; a
    // return (12) and a new entry (12) would add 18.
    preempt(CpuModel::Pessimistic, 17);
    preempt(CpuModel::Typical, 15);
}

fn preempt(model: CpuModel, between: u32) {
    let mut m = load_with("preempt", model);
    let l = run(&mut m);
    assert_eq!(l.len(), 9, "{l:x?}");
    // IRQ1 preempted IRQ0 between 'a' and 'b'; IRQ2 waited for IRQ0's end and ran
    // before thread mode resumed ('T' last).
    assert_eq!(
        [l[0], l[1], l[2], l[3], l[7], l[8]],
        [ch('A'), ch('a'), ch('B'), ch('b'), ch('C'), ch('T')]
    );
    let (irq0_sp, irq2_sp) = (l[4], l[6]);
    assert_eq!(irq0_sp, irq2_sp, "tail-chaining keeps IRQ0's frame");
    assert_eq!(
        irq0_sp,
        0x2000_5000 - 32,
        "one 8-word frame below the initial SP"
    );
    let irq0_end = word(&m, LOG + 0x100);
    let irq2_first = l[5];
    let d = irq2_first.wrapping_sub(irq0_end);
    assert_eq!(d, between, "cycles between the handlers ({model:?})");
}

#[test]
fn basepri_and_primask_hold_interrupts_back_and_lowering_them_takes_them_at_once() {
    let mut m = load("masks");
    let l = run(&mut m);
    let want: Vec<u32> = "mBnAupBq".chars().map(ch).collect();
    assert_eq!(
        l,
        want,
        "{:?}",
        l.iter().map(|&c| c as u8 as char).collect::<String>()
    );
}

/// One run of the late-arrival program with TIM2's update due `d` - 0.5 cycles after
/// SysTick's: (TIM2's handler started first, both handlers saw the same SP at entry).
fn late(d: u32) -> (bool, bool) {
    let mut m = load("late");
    m.uc.mem_write(0x2000_1000, &d.to_le_bytes()).unwrap();
    let l = run(&mut m);
    assert_eq!(l.len(), 2, "d = {d}: {l:x?}");
    let (systick_cycles, systick_sp) = (word(&m, LOG + 0x100), word(&m, LOG + 0x104));
    let (tim2_cycles, tim2_sp) = (word(&m, LOG + 0x108), word(&m, LOG + 0x10C));
    (tim2_cycles < systick_cycles, tim2_sp == systick_sp)
}

#[test]
fn an_interrupt_arriving_while_another_is_stacked_is_taken_first_on_the_same_frame() {
    // TIM2 due before SysTick: taken first, SysTick follows by tail-chaining.
    assert_eq!(late(0), (true, true));
    let runs: Vec<(u32, (bool, bool))> = (1..40).map(|d| (d, late(d))).collect();
    // TIM2 due after SysTick's entry began: while the frame is stacked (12 cycles,
    // entry begins at the first block boundary after SysTick's event) it arrives
    // late and is taken first on the same frame; after that it preempts SysTick's
    // handler (a frame of its own).
    let late_ones: Vec<u32> = runs
        .iter()
        .filter(|(_, r)| *r == (true, true))
        .map(|(d, _)| *d)
        .collect();
    let nested: Vec<u32> = runs
        .iter()
        .filter(|(_, r)| *r == (false, false))
        .map(|(d, _)| *d)
        .collect();
    assert_eq!(
        late_ones.len() + nested.len(),
        runs.len(),
        "every run is one or the other: {runs:?}"
    );
    let switch = nested[0];
    assert!(
        late_ones.iter().all(|&d| d < switch) && nested.iter().all(|&d| d >= switch),
        "{runs:?}"
    );
    // The window is the 12-cycle entry (plus where in the waiting loop's 6-cycle
    // block SysTick's event fell).
    assert!(
        (13..=19).contains(&switch),
        "late arrival up to d = {switch}"
    );
}

#[test]
fn a_missed_watchdog_reload_resets_the_mcu_10_1_ms_after_the_last_one() {
    let mut m = load("iwdg");
    let l = run(&mut m);
    assert_eq!(m.state().watchdog_resets, 1);
    assert_eq!(l.len(), 3, "{l:x?}");
    // Power-on: PORRSTF and PINRSTF; after the watchdog's reset IWDGRSTF as well.
    assert_eq!(l[0], 0x0C00_0000);
    assert_eq!(l[2], 0x2C00_0000);
    // The last reload, by the cycle counter (8 MHz), to the reset: (100 + 1) x 4 LSI
    // periods of 25 us = 10.1 ms (the reset's own start-up takes a few instructions).
    let last_reload = u64::from(l[1]) * (T_PER_S / 8_000_000);
    let end = m.now();
    let to_reset = end - last_reload;
    let want = 10 * T_PER_MS + 100 * T_PER_US;
    assert!(
        to_reset >= want && to_reset < want + 20 * T_PER_US,
        "{:.1} us from the last reload to the end",
        to_reset as f64 / T_PER_US as f64
    );
    // Five reloads ~5 ms apart kept it from firing before.
    assert!(last_reload > 20 * T_PER_MS);
}

#[test]
fn an_interrupt_inside_an_it_block_leaves_the_handler_unconditional_and_the_rest_conditional() {
    let mut m = load("itstate");
    let l = run(&mut m);
    assert_eq!(l.len(), 4, "{l:x?}");
    // The handler's first instruction ran (7), and the interrupted block's `movne`
    // stayed skipped after the return (r5 = 1, not 2).
    assert_eq!([l[0], l[2], l[3]], [7, 1, ch('e')], "{l:x?}");
    // The frame's xPSR: Z and C from the `cmp`, the Thumb bit, and the IT state of
    // the one instruction left (`ne`: ITSTATE 0x18, bits 15:10 and 26:25).
    assert_eq!(l[1], 0x6000_0000 | 1 << 24 | 0x18 << 8, "{:08x}", l[1]);
}

#[test]
fn exception_entry_aligns_the_frame_to_8_bytes_only_with_ccr_stkalign() {
    let mut m = load("stkalign");
    let l = run(&mut m);
    let thread_sp = 0x2000_5000 - 4;
    assert_eq!(
        l,
        [
            // STKALIGN clear (reset): the frame right below the SP, 4 mod 8.
            thread_sp - 32,
            0,
            // STKALIGN set: a padding word, the stacked xPSR's bit 9 set.
            thread_sp - 4 - 32,
            1,
            // Both returns gave the thread its SP back.
            thread_sp,
        ],
        "{l:x?}"
    );
}
