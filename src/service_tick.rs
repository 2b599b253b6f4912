//! The service tick's clock: milliseconds since boot, counted by the SysTick handler
//! (its only writer) and read by every task and by the step side, which starts the
//! step timer on the schedule of the tick whose preparation queued a start from rest
//! (`ticks_since_tick`). Here, not in the RTIC app, because the step side
//! (`steps::BoardSide`) needs it in the middle of a preparation.

use core::sync::atomic::{AtomicU32, Ordering};

/// Milliseconds since boot: counted by the tick, read by every task.
static NOW_MS: AtomicU32 = AtomicU32::new(0);
/// How far into SysTick's period the last tick's handler ran (cycles): the service
/// tick's time, from which a start from rest runs (`ticks_since_tick`).
static TICK_TAKEN: AtomicU32 = AtomicU32::new(0);

/// Milliseconds since boot.
pub fn now_ms() -> u32 {
    NOW_MS.load(Ordering::Relaxed)
}

/// The tick's own count, from its handler (the only writer): the new millisecond.
pub fn count_tick() -> u32 {
    TICK_TAKEN.store(into_period(), Ordering::Relaxed);
    let now = NOW_MS.load(Ordering::Relaxed).wrapping_add(1);
    NOW_MS.store(now, Ordering::Relaxed);
    now
}

/// SysTick's count since its reload when the tick's handler ran (a flash stall
/// delays it: the ticks that fell in the stall are taken as one when it ends).
fn into_period() -> u32 {
    // SAFETY: read-only register reads.
    let syst = unsafe { &*cortex_m::peripheral::SYST::PTR };
    syst.rvr.read() - syst.cvr.read()
}

/// SysTick's period, the tick count and SysTick's counts since that tick's handler
/// ran, read together. A SysTick whose handler has not run yet (masked by a
/// critical section) is counted: its period began, so
/// the counts since the last tick taken run on past it. Read without that, the time
/// came out a whole period short (`stamp`), or wrapped (`ticks_since_tick`, then
/// bounded by a stop stamped a period early): a start from rest after a Z pen's
/// trip began its first period as if 0.9 ms had gone, and its step came 0.9 ms
/// early (`.ci/emu-random`, seed 1729238220).
fn snapshot() -> (u32, u32, u32) {
    // SAFETY: read-only register reads.
    let period = unsafe { (*cortex_m::peripheral::SYST::PTR).rvr.read() } + 1;
    loop {
        let ms = NOW_MS.load(Ordering::Relaxed);
        let taken = TICK_TAKEN.load(Ordering::Relaxed);
        let pending = cortex_m::peripheral::SCB::is_pendst_pending();
        let into = into_period();
        // The same tick throughout: no handler ran, no reload came in between.
        if pending == cortex_m::peripheral::SCB::is_pendst_pending()
            && ms == NOW_MS.load(Ordering::Relaxed)
        {
            let since = if pending {
                into.wrapping_add(period).wrapping_sub(taken)
            } else {
                into.wrapping_sub(taken)
            };
            return (period, ms, since);
        }
    }
}

/// Step-timer ticks (72 MHz, the core clock's) since the service tick `ms` was
/// taken (its handler ran), plus whole periods if ticks have come since.
pub fn ticks_since_tick(ms: u32) -> u32 {
    let (period, now, into) = snapshot();
    now.wrapping_sub(ms)
        .saturating_mul(period)
        .saturating_add(into)
}

/// Now, in step-timer ticks on the service tick's clock (wrapping every 59.6 s): the
/// same measure as [`ticks_since_tick`], so that `stamp() - ms * period` is that.
pub fn stamp() -> u32 {
    let (period, now, into) = snapshot();
    now.wrapping_mul(period).wrapping_add(into)
}
