//! Interrupt-cost harness: runs the four reference programs (bench/*.nc) through the
//! real core code built for thumbv7m - planner, segment preparation, and the step
//! interrupt's work exactly as the firmware's TIM2 handler does it (register accesses
//! included, at the real TIM2/GPIOA addresses) - so `measure.py` can count the
//! instructions of every call in an emulator.
//!
//! Measured functions: `bench_tick` (the update interrupt: pulse, fetch the next event,
//! program the period), `bench_pulse_end` (the compare interrupt: step pins low,
//! directions for the next step) and `bench_prepare` (one run of the segment
//! preparation). `BENCH_RESULT` = [steps, update interrupts, commands prepared, prepare
//! calls, programs, final X of the last program, final Y, 0].
#![no_std]
#![no_main]

use core::ptr::{addr_of_mut, read_volatile, write_volatile};
use core::sync::atomic::{AtomicBool, Ordering};
use defmt_rtt as _;
use heapless::spsc::{Consumer, Producer, Queue};
use inkstep_core::planner::{Planner, PlannerConfig};
use inkstep_core::refprog::RefProgram;
use inkstep_core::stepper::drive::STEP_QUEUE;
use inkstep_core::stepper::exec::{Executor, IsrOut};
use inkstep_core::stepper::prep::{Prep, PrepConfig};
use inkstep_core::stepper::StepCmd;

/// The reference programs without their trailing `G4 P0` lines (build.rs strips them:
/// they only keep a streaming sender busy, and flash is tight).
const PROGRAMS: [&str; 4] = [
    include_str!(concat!(env!("OUT_DIR"), "/star.nc")),
    include_str!(concat!(env!("OUT_DIR"), "/circle.nc")),
    include_str!(concat!(env!("OUT_DIR"), "/sine.nc")),
    include_str!(concat!(env!("OUT_DIR"), "/spiral.nc")),
];

const TIM2_SR: *mut u32 = 0x4000_0010 as *mut u32;
const TIM2_ARR: *mut u32 = 0x4000_002C as *mut u32;
const GPIOA_BSRR: *mut u32 = 0x4001_0810 as *mut u32;
const STEP_ALL: u32 = 0b111;
const DIR_SHIFT: u32 = 3;

#[no_mangle]
pub static mut BENCH_RESULT: [u32; 8] = [0; 8];
static ESTOP: AtomicBool = AtomicBool::new(false);
static mut STEPS: Queue<StepCmd, STEP_QUEUE> = Queue::new();

/// The firmware's step-interrupt state (see src/main.rs).
pub struct Isr {
    exec: Executor,
    rx: Consumer<'static, StepCmd>,
    next: IsrOut,
    dir_after: u8,
}

/// Update interrupt: the firmware's TIM2 update path. Returns 0 when the timer stops.
#[inline(never)]
#[no_mangle]
pub fn bench_tick(s: &mut Isr) -> u32 {
    // SAFETY: plain register accesses at the real addresses (emulated memory here).
    unsafe {
        let sr = read_volatile(TIM2_SR);
        write_volatile(TIM2_SR, !(sr & 0b11));
    }
    if ESTOP.load(Ordering::SeqCst) {
        s.exec.halt();
        return 0;
    }
    let now = s.next;
    if now.step != 0 {
        // SAFETY: as above.
        unsafe { write_volatile(GPIOA_BSRR, u32::from(now.step)) };
    }
    s.dir_after = now.dir;
    if now.reload == 0 {
        return 0;
    }
    s.next = s.exec.on_interrupt(&mut s.rx);
    if s.next.reload != 0 {
        // SAFETY: as above.
        unsafe { write_volatile(TIM2_ARR, s.next.reload.clamp(2, 0x1_0000) - 1) };
    }
    1
}

/// Compare interrupt: end of the pulse, directions for the next step.
#[inline(never)]
#[no_mangle]
pub fn bench_pulse_end(s: &mut Isr) {
    let d = u32::from(s.dir_after & 0b111);
    // SAFETY: as above.
    unsafe {
        let sr = read_volatile(TIM2_SR);
        write_volatile(TIM2_SR, !(sr & 0b11));
        write_volatile(
            GPIOA_BSRR,
            (d << DIR_SHIFT) | ((STEP_ALL | ((!d & 0b111) << DIR_SHIFT)) << 16),
        );
    }
}

/// One run of the segment preparation; returns the commands it queued.
#[inline(never)]
#[no_mangle]
pub fn bench_prepare(
    prep: &mut Prep,
    planner: &mut Planner,
    tx: &mut Producer<'static, StepCmd>,
) -> u32 {
    let before = tx.len();
    prep.fill(planner, tx);
    (tx.len() - before) as u32
}

#[cortex_m_rt::entry]
fn main() -> ! {
    // SAFETY: the only reference to the queue, taken once.
    let q = unsafe { &mut *addr_of_mut!(STEPS) };
    let (mut tx, rx) = q.split();
    let mut isr = Isr {
        exec: Executor::new([0; 3], 0x1_0000),
        rx,
        next: IsrOut::default(),
        dir_after: 0,
    };
    let mut r = [0u32; 8];
    for text in PROGRAMS {
        let prog = RefProgram::new(text, PlannerConfig::default());
        let mut planner = Planner::new(prog.config(), [0; 3]);
        let mut prep = Prep::new(
            PrepConfig {
                timer_hz: 2_000_000,
                ..PrepConfig::default()
            },
            [0; 3],
        );
        isr.exec = Executor::new([0; 3], 0x1_0000);
        let mut moves = prog.peekable();
        let mut running = false;
        loop {
            while !planner.is_full() {
                match moves.next() {
                    Some(m) => {
                        let _ = planner.push(&m);
                    }
                    None => break,
                }
            }
            if tx.len() < STEP_QUEUE / 2 {
                r[2] += bench_prepare(&mut prep, &mut planner, &mut tx);
                r[3] += 1;
            }
            if !running {
                match isr.exec.start(&mut isr.rx) {
                    Some(first) => {
                        isr.dir_after = first.dir;
                        isr.next = isr.exec.on_interrupt(&mut isr.rx);
                        running = true;
                    }
                    None if prep.is_idle(&planner) && moves.peek().is_none() => break,
                    None => continue,
                }
            }
            if isr.next.step != 0 {
                r[0] += 1;
            }
            r[1] += 1;
            if bench_tick(&mut isr) == 0 {
                running = false;
            }
            bench_pulse_end(&mut isr);
        }
        r[4] += 1;
        let p = isr.exec.position();
        r[5] = p[0] as u32;
        r[6] = p[1] as u32;
    }
    // SAFETY: single-threaded; the emulator reads the record after the breakpoint.
    unsafe { *addr_of_mut!(BENCH_RESULT) = r };
    loop {
        cortex_m::asm::bkpt();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        cortex_m::asm::bkpt();
    }
}
