//! Interrupt-cost bench: runs the firmware's real step path on a Cortex-M3 (in the
//! unicorn emulator, see measure.py) over the reference programs in bench/*.nc.
//!
//! The programs go through the core's controller (`Controller::service` with the host's
//! byte rings, as the firmware's protocol task runs it), protocol and G-code
//! interpreter into the pipeline (planner + segment preparation), whose step commands cross the same SPSC queue to
//! the firmware's `StepOutput::on_interrupt` (src/steps.rs), i.e. the whole TIM2
//! interrupt body with its register accesses. The emulator has no timer, so before each
//! call the bench sets the status flag the hardware would (the update event; the timer
//! draws the pulses itself, so there is no other event) and, before an update, stops
//! the counter as the step timer's one-pulse mode does. measure.py charges every
//! instruction executed inside `bench_tick` (update event), `bench_kick` (software pend)
//! and `bench_prepare` to that call.
#![no_std]
#![no_main]
#![deny(clippy::undocumented_unsafe_blocks)]

use defmt_rtt as _;
use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use inkstep::board::{self, StepPins};
use inkstep::steps::{self, BoardSide, StepOutput};
use inkstep_core::controller::{Controller, HostLink, HOST_RX_RING, HOST_TX_RING};
use inkstep_core::machine::PinLevels;
use inkstep_core::pipeline::{Pipeline, StepSide};
use inkstep_core::ring::ByteRing;
use inkstep_core::settings::Settings;
use inkstep_core::settings_store::SettingsStore;
use inkstep_core::stepper::exec::Executor;
use inkstep_core::stepper::output::OutputConfig;
use inkstep_core::stepper::prep::PrepConfig;
use inkstep_core::stepper::queue::StepCmdQueue;
use inkstep_core::stepper::MAX_RELOAD;
use stm32f1xx_hal::{gpio::PinState, pac, prelude::*};

const PROGRAMS: [&[u8]; 5] = [
    include_bytes!("../../star.nc"),
    include_bytes!("../../circle.nc"),
    include_bytes!("../../sine.nc"),
    include_bytes!("../../spiral.nc"),
    include_bytes!("../../fast.nc"),
];

/// Per program: step events, interrupts, final X, final Y, the steps summed over the
/// axes, the interrupts that found the queue empty before the job was done, and the
/// virtual milliseconds the program took (read by measure.py).
#[no_mangle]
pub static mut BENCH_RESULT: [[u32; 8]; PROGRAMS.len()] = [[0; 8]; PROGRAMS.len()];

/// The program running now (measure.py charges every call to it).
#[no_mangle]
pub static mut BENCH_PROGRAM: u32 = 0;

/// The protocol's replies (last 1 KB), for measure.py to show when a program fails.
#[no_mangle]
pub static mut BENCH_LOG: [u8; 1024] = [0; 1024];
static mut LOG_AT: usize = 0;

fn log(bytes: &[u8]) {
    // SAFETY: single-threaded bench.
    unsafe {
        let buf = &mut *core::ptr::addr_of_mut!(BENCH_LOG);
        let at = &mut *core::ptr::addr_of_mut!(LOG_AT);
        for &b in bytes {
            if let Some(slot) = buf.get_mut(*at % 1024) {
                *slot = b;
            }
            *at += 1;
        }
    }
}

/// The input pins at rest with the board's wiring (nothing pressed).
const PINS_AT_REST: PinLevels = PinLevels {
    estop: false,
    limits: [Some(false), Some(false), None],
    feed_hold: true,
    cycle_start: true,
};

/// The settings store's flash: two erased 1 KB pages in RAM, NOR semantics (the
/// programs change no setting, so nothing is written in practice).
struct RamFlash([u8; 2 * 1024]);

impl ErrorType for RamFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for RamFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let at = offset as usize;
        let src = self
            .0
            .get(at..at + bytes.len())
            .ok_or(NorFlashErrorKind::OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.0.len()
    }
}

impl NorFlash for RamFlash {
    const WRITE_SIZE: usize = 2;
    const ERASE_SIZE: usize = 1024;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.0
            .get_mut(from as usize..to as usize)
            .ok_or(NorFlashErrorKind::OutOfBounds)?
            .fill(0xFF);
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let at = offset as usize;
        let dst = self
            .0
            .get_mut(at..at + bytes.len())
            .ok_or(NorFlashErrorKind::OutOfBounds)?;
        for (d, b) in dst.iter_mut().zip(bytes) {
            *d &= b;
        }
        Ok(())
    }
}

const TIM2_SR: *mut u32 = 0x4000_0010 as *mut u32;
const UIF: u32 = 1;
const TIM2_ARR: *const u32 = 0x4000_002C as *const u32;
const TIM2_CR1: *mut u32 = 0x4000_0000 as *mut u32;
const TIM3_CNT: *mut u32 = 0x4000_0424 as *mut u32;

/// The TIM2 interrupt handler exactly as RTIC generates it for the firmware's priority-6
/// `step` task (`rtic::export::run` saves and restores BASEPRI around the body), compiled
/// once as in the firmware. measure.py charges each call of this function, classified by
/// the status flag at entry: `update` (a period ended) or `pend` (software pend).
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_isr(out: &mut StepOutput) {
    rtic::export::run(6, || out.on_interrupt());
}

/// The TIM2 interrupt at an update event (period end: next command, pulses armed, next
/// wait), as the firmware runs it. Each wrapper first sets the status flag the hardware
/// would (one store, counted), which also keeps the wrappers distinct.
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_tick(out: &mut StepOutput) {
    raise(UIF);
    bench_isr(out);
}

/// The TIM2 interrupt pended by the preparation task to start the timer.
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_kick(out: &mut StepOutput) {
    raise(0);
    bench_isr(out);
}

/// One run of segment preparation, as the firmware's prepare task does it.
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_prepare(pipeline: &mut Pipeline<BoardSide>) {
    pipeline.fill();
}

/// The period the step interrupt just programmed (TIM2 ARR + 1), timer ticks.
fn period() -> u64 {
    // SAFETY: the emulator maps the timer registers as plain memory.
    u64::from(unsafe { core::ptr::read_volatile(TIM2_ARR) }) + 1
}

fn raise(flags: u32) {
    // SAFETY: the emulator maps the timer registers as plain memory.
    unsafe { core::ptr::write_volatile(TIM2_SR, flags) }
}

/// What the timer does itself at an update event in one-pulse mode (the step timer's):
/// the counter stops, CEN cleared. Outside the measured calls.
fn period_ends() {
    // SAFETY: the emulator maps the timer registers as plain memory.
    unsafe { core::ptr::write_volatile(TIM2_CR1, core::ptr::read_volatile(TIM2_CR1) & !1) }
}

/// The step timer's schedule clock (TIM3, one count per two ticks) as the interrupt
/// reads it when it runs at virtual tick `t`: about 100 ticks after its event (the
/// entry and the work before the read), so it finds itself on time as on the board.
fn clock_at(t: u64) {
    // SAFETY: the emulator maps the timer registers as plain memory.
    unsafe { core::ptr::write_volatile(TIM3_CNT, (((t + 100) >> 1) & 0xFFFF) as u32) }
}

#[cortex_m_rt::entry]
fn main() -> ! {
    // SAFETY: nothing else owns the peripherals in this bench.
    let dp = unsafe { pac::Peripherals::steal() };
    let mut rcc = dp.RCC.constrain();
    let mut gpioa = dp.GPIOA.split(&mut rcc);
    let pins = StepPins {
        pins: [
            gpioa.pa0.into_push_pull_output(&mut gpioa.crl).erase(),
            gpioa.pa1.into_push_pull_output(&mut gpioa.crl).erase(),
            gpioa.pa2.into_push_pull_output(&mut gpioa.crl).erase(),
            gpioa.pa3.into_push_pull_output(&mut gpioa.crl).erase(),
            gpioa.pa4.into_push_pull_output(&mut gpioa.crl).erase(),
            gpioa.pa5.into_push_pull_output(&mut gpioa.crl).erase(),
            gpioa.pa6.into_push_pull_output(&mut gpioa.crl).erase(),
            gpioa.pa7.into_push_pull_output(&mut gpioa.crl).erase(),
        ],
        enable: gpioa
            .pa9
            .into_push_pull_output_with_state(&mut gpioa.crh, PinState::High),
    };
    let (port, mut timer) = board::step_outputs(pins, dp.TIM2, dp.TIM3);
    timer.set_pulse_ticks(10 * 72);
    let (mut port, mut timer) = (Some(port), Some(timer));
    // The interrupt's configuration word is written at boot, as in the firmware (so
    // the bench pays its load like the firmware does).
    let settings = Settings::default();
    steps::set_output_config(&OutputConfig::from(&settings));

    static mut QUEUES: [StepCmdQueue; PROGRAMS.len()] =
        [const { StepCmdQueue::new() }; PROGRAMS.len()];
    let prep = PrepConfig {
        timer_hz: board::STEP_TIMER_HZ,
        ..PrepConfig::default()
    };

    for (p, prog) in PROGRAMS.iter().enumerate() {
        // Each program runs on a freshly booted machine, as in the simulator's runs.
        // SAFETY: each queue is split once, before anything else uses it.
        let queue = unsafe { &mut (*core::ptr::addr_of_mut!(QUEUES))[p] };
        let (tx, rx) = queue.split();
        let (Some(pins), Some(tim)) = (port.take(), timer.take()) else {
            break;
        };
        let mut out = steps::install(Executor::new([0; 3], MAX_RELOAD), rx, pins, tim);
        let mut pipeline = Pipeline::new(&settings, prep, BoardSide { tx });
        let mut ctl = Controller::new(settings.clone(), 0);
        let Ok(mut store) = SettingsStore::new(RamFlash([0xFF; 2 * 1024]), 0..2 * 1024) else {
            break;
        };
        // The USB task's byte rings between the host and the protocol task.
        let mut host_rx: ByteRing<HOST_RX_RING> = ByteRing::new();
        let mut host_tx: ByteRing<HOST_TX_RING> = ByteRing::new();
        let (mut usb_rx_in, mut usb_rx_out) = host_rx.split();
        let (mut usb_tx_in, mut usb_tx_out) = host_tx.split();
        // SAFETY: single-threaded bench; measure.py charges each call to this program.
        unsafe { core::ptr::write_volatile(core::ptr::addr_of_mut!(BENCH_PROGRAM), p as u32) };
        let (mut sent, mut events, mut irqs, mut dry) = (0usize, 0u32, 0u32, 0u32);
        let mut axis_steps = 0u32;
        let mut sink = [0u8; 128];
        // Virtual time in timer ticks: the step interrupts happen when the periods the
        // interrupt programs end; the protocol and the preparation run every
        // millisecond, as the firmware's SysTick pends them.
        let (mut next_ms, mut next_irq) = (0u64, None::<u64>);
        loop {
            if let Some(at) = next_irq.filter(|&at| at < next_ms) {
                let before = steps::position();
                period_ends();
                clock_at(at);
                bench_tick(&mut out);
                irqs += 1;
                let after = steps::position();
                if after != before {
                    events += 1;
                    axis_steps +=
                        before.iter().zip(after).filter(|(a, b)| **a != *b).count() as u32;
                }
                next_irq = out.timer.is_running().then(|| at + period());
                if next_irq.is_none() && pipeline.in_move() {
                    // The queue ran dry while a move still had steps to make (a dwell or
                    // a pen move stops the timer on purpose).
                    dry += 1;
                }
                continue;
            }
            let now = (next_ms / 72_000) as u32;
            next_ms += 72_000;
            // The USB task: the host's bytes in as far as the ring has room.
            if sent < prog.len() {
                sent += usb_rx_in.push(prog.get(sent..).unwrap_or(&[]));
            }
            // The protocol task: the controller's service until no line may run now,
            // the replies out.
            loop {
                let host = HostLink {
                    rx: &mut usb_rx_out,
                    tx: &mut usb_tx_in,
                    port_open: true,
                };
                let done = ctl.service(
                    host,
                    PINS_AT_REST,
                    &steps::HALT,
                    &mut store,
                    &mut pipeline,
                    now,
                );
                loop {
                    let n = usb_tx_out.pop_into(&mut sink);
                    if n == 0 {
                        break;
                    }
                    log(sink.get(..n).unwrap_or(&[]));
                }
                if !done.again(now, now) {
                    break;
                }
            }
            bench_prepare(&mut pipeline);
            if next_irq.is_none() && pipeline.side().queued() > 0 {
                // Start the timer as the firmware's kick does (a pend with no flags).
                clock_at(next_ms - 72_000);
                bench_kick(&mut out);
                next_irq = out.timer.is_running().then(|| next_ms - 72_000 + period());
            }
            // Done when every byte was taken AND executed (nothing left in the protocol's
            // receive buffer), and the machine is at rest.
            let drained = ctl.protocol().rx_free() == inkstep_core::protocol::RX_BUFFER_SIZE;
            let done = sent >= prog.len()
                && usb_rx_out.is_empty()
                && drained
                && next_irq.is_none()
                && pipeline.side().queued() == 0;
            if done && inkstep_core::machine::MotionControl::is_idle(&pipeline) {
                break;
            }
        }
        let pos = steps::position();
        port = Some(out.port);
        timer = Some(out.timer);
        // SAFETY: single-threaded bench; measure.py reads this after the run.
        unsafe {
            let r = &mut (*core::ptr::addr_of_mut!(BENCH_RESULT))[p];
            *r = [
                events,
                irqs,
                pos[0] as u32,
                pos[1] as u32,
                axis_steps,
                dry,
                (next_ms / 72_000) as u32,
                0,
            ];
        }
    }
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
