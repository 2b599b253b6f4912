//! inkstep's change to stm32-usbd 0.8.0: the sections that upstream runs inside
//! `cortex_m::interrupt::free` (every interrupt masked, about 36 instructions per byte
//! of a packet copy) run here with BASEPRI raised to a level the application sets, so
//! that interrupts above the USB's own priority still preempt them
//! (stm32-rs/stm32-usbd issue 32). With no level set, the section masks every
//! interrupt, as upstream does.

use core::sync::atomic::{compiler_fence, AtomicU8, Ordering};
use cortex_m::interrupt::CriticalSection;

/// The BASEPRI value the sections raise to; 0: mask every interrupt (PRIMASK).
static LEVEL: AtomicU8 = AtomicU8::new(0);

/// Let the bus's sections mask only the interrupts whose priority is at or below
/// `basepri` (a hardware priority value, as BASEPRI takes it; 0 restores masking
/// everything).
///
/// # Safety
///
/// Every use of the bus and its endpoints (poll, read, write, ...) must then come from
/// code whose execution priority is at or below that level: the sections exclude only
/// those, and the bus's shared state is then never touched by two contexts at once.
pub unsafe fn mask_at_or_below(basepri: u8) {
    LEVEL.store(basepri, Ordering::SeqCst);
}

/// Run `f` inside the bus's section (see [`mask_at_or_below`]).
#[inline(always)]
pub(crate) fn free<R>(f: impl FnOnce(&CriticalSection) -> R) -> R {
    let saved = enter();
    compiler_fence(Ordering::SeqCst);
    // SAFETY: the section is entered: every interrupt masked (no level set), or the
    // application's promise (`mask_at_or_below`): every context that uses the bus
    // runs at a priority that the raised BASEPRI now holds off.
    let r = f(unsafe { &CriticalSection::new() });
    compiler_fence(Ordering::SeqCst);
    exit(saved);
    r
}

/// What [`exit`] restores: the BASEPRI before the section, or with [`PRIMASK_USED`]
/// whether PRIMASK was clear before it (bit 0).
const PRIMASK_USED: u32 = 1 << 31;

/// Enter a section (out of line: one copy for every section of the crate).
#[inline(never)]
fn enter() -> u32 {
    let level = LEVEL.load(Ordering::Relaxed);
    if level == 0 {
        let was_enabled = cortex_m::register::primask::read().is_active();
        cortex_m::interrupt::disable();
        return PRIMASK_USED | u32::from(was_enabled);
    }
    let before = cortex_m::register::basepri::read();
    // Raises BASEPRI only (a section inside a higher one keeps the higher).
    cortex_m::register::basepri_max::write(level);
    u32::from(before)
}

/// Leave the section [`enter`] began.
#[inline(never)]
fn exit(saved: u32) {
    if saved & PRIMASK_USED != 0 {
        if saved & 1 != 0 {
            // SAFETY: interrupts were enabled before the section.
            unsafe { cortex_m::interrupt::enable() };
        }
    } else {
        // SAFETY: restores the value `enter` read; sections nest, so no section
        // entered after it is still open.
        unsafe { cortex_m::register::basepri::write(saved as u8) };
    }
}
