//! What every firmware image does when something goes wrong: every motor driver is
//! disabled before anything else. The binaries' `#[panic_handler]` and `HardFault`
//! handler are one-line calls into here (a handler defined in this library would also
//! land in the on-target tests, which use panic-probe).

use crate::board;
use core::sync::atomic::{AtomicBool, Ordering};

/// Set on the first panic: a panic inside the panic path (the defmt logger already
/// taken, say) skips the log instead of recursing, so the panic path's stack is
/// bounded (`.ci/stack-depth` counts it once).
static PANICKING: AtomicBool = AtomicBool::new(false);

/// The panic path: drivers off, then what panic-probe does (print over defmt, then an
/// undefined instruction escalated to HardFault, so that probe-rs stops and shows the
/// backtrace). panic-probe itself offers no hook that runs first.
pub fn on_panic(info: &core::panic::PanicInfo) -> ! {
    board::emergency_outputs_off();
    cortex_m::interrupt::disable();
    // Interrupts are off: a plain load and store cannot be torn by another panic.
    let again = PANICKING.load(Ordering::Relaxed);
    PANICKING.store(true, Ordering::Relaxed);
    // The location only: formatting the message would link core::fmt's machinery
    // (and every panic site's argument formatting) into the image.
    match info.location() {
        _ if again => {}
        Some(l) => defmt::error!("panic at {}:{}", l.file(), l.line()),
        None => defmt::error!("panic"),
    }
    // SAFETY: SHCSR is the System Handler Control and State Register; clearing
    // USGFAULTENA only makes the undefined instruction below a HardFault.
    unsafe {
        const SHCSR: *mut u32 = 0xE000_ED24_usize as *mut u32;
        core::ptr::write_volatile(SHCSR, core::ptr::read_volatile(SHCSR) & !(1 << 18));
    }
    cortex_m::asm::udf()
}

/// The HardFault path: drivers off (again, if a panic led here), then stay put for the
/// probe until the watchdog resets the board.
pub fn on_hard_fault() -> ! {
    board::emergency_outputs_off();
    loop {
        cortex_m::asm::bkpt();
    }
}
