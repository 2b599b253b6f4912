//! The Cortex-M3 system control space as the ARMv7-M Architecture Reference Manual
//! describes it (B1.5 exception model, B3.2 SCB, B3.3 SysTick, B3.4 NVIC): which
//! exceptions are enabled, pending and active, their priorities, and which one the
//! processor takes next. Pure state and arithmetic; the machine (`machine.rs`) does the
//! stacking and unstacking on the CPU.
//!
//! Implemented priority bits: 4 (STM32F103, PM0056). Exceptions are numbered as in the
//! vector table: 2 NMI, 3 HardFault, 11 SVCall, 14 PendSV, 15 SysTick, 16 + n IRQ n.

use crate::clock::{t_per_cycle, T_PER_US};

/// IRQs of the medium-density STM32F103 (RM0008 table 63: 0..42).
pub const IRQS: usize = 43;
pub const EXC_COUNT: usize = 16 + IRQS;
pub const HARDFAULT: usize = 3;
pub const SVCALL: usize = 11;
pub const PENDSV: usize = 14;
pub const SYSTICK: usize = 15;
/// Priority bits implemented (the upper nibble of each priority byte).
const PRIO_MASK: u8 = 0xF0;

/// A register the system control space does not have (or a size it cannot take).
#[derive(Debug)]
pub struct Unknown;

pub struct Nvic {
    pub enabled: [bool; EXC_COUNT],
    pub pending: [bool; EXC_COUNT],
    pub active: [bool; EXC_COUNT],
    /// Programmed priority byte of each exception (only 4..15 and IRQs are writable).
    prio: [u8; EXC_COUNT],
    /// The active exceptions, innermost last: the stack the machine returns through.
    pub nesting: Vec<usize>,
    pub vtor: u32,
    aircr_prigroup: u32,
    pub scr: u32,
    pub ccr: u32,
    pub cfsr: u32,
    pub hfsr: u32,
    /// AIRCR.SYSRESETREQ was written: the board resets.
    pub reset_requested: bool,
    pub systick: SysTick,
}

impl Nvic {
    pub fn new() -> Nvic {
        let mut enabled = [false; EXC_COUNT];
        // NMI, HardFault, SVCall, PendSV and SysTick are always enabled (SysTick's
        // interrupt is gated by its own TICKINT).
        for e in [2, HARDFAULT, SVCALL, 12, PENDSV, SYSTICK] {
            enabled[e] = true;
        }
        Nvic {
            enabled,
            pending: [false; EXC_COUNT],
            active: [false; EXC_COUNT],
            prio: [0; EXC_COUNT],
            nesting: Vec::new(),
            vtor: 0,
            aircr_prigroup: 0,
            scr: 0,
            // Cortex-M3 r1p1 (the STM32F103's core): STKALIGN resets to 0.
            ccr: 0,
            cfsr: 0,
            hfsr: 0,
            reset_requested: false,
            systick: SysTick::new(),
        }
    }

    /// The priority of exception `e` as a signed number: lower is more urgent.
    pub fn priority(&self, e: usize) -> i32 {
        match e {
            1 => -3,
            2 => -2,
            HARDFAULT => -1,
            _ => i32::from(self.prio[e]),
        }
    }

    /// The group priority of exception `e` (what preemption compares).
    pub fn group_priority(&self, e: usize) -> i32 {
        self.group(self.priority(e))
    }

    /// The group priority: the bits above the PRIGROUP split (B1.5.4).
    fn group(&self, prio: i32) -> i32 {
        if prio < 0 {
            return prio;
        }
        let sub_bits = self.aircr_prigroup + 1;
        (prio >> sub_bits) << sub_bits
    }

    /// The execution priority (B1.5.4): the most urgent active exception's group
    /// priority, lowered by BASEPRI, PRIMASK and FAULTMASK. 256 in thread mode.
    pub fn execution_priority(&self, primask: bool, basepri: u32, faultmask: bool) -> i32 {
        let mut p = 256;
        for &e in &self.nesting {
            p = p.min(self.group(self.priority(e)));
        }
        let basepri = (basepri as u8 & PRIO_MASK) as i32;
        if basepri != 0 {
            p = p.min(self.group(basepri));
        }
        if primask {
            p = p.min(0);
        }
        if faultmask {
            p = p.min(-1);
        }
        p
    }

    /// The pending, enabled exception that would be taken next, with its group
    /// priority: the most urgent, the lowest number among equals (B1.5.4).
    pub fn highest_pending(&self) -> Option<(usize, i32)> {
        let mut best: Option<(usize, i32, i32)> = None;
        for e in 2..EXC_COUNT {
            if self.pending[e] && self.enabled[e] {
                let p = self.priority(e);
                if best.is_none_or(|(_, _, bp)| p < bp) {
                    best = Some((e, self.group(p), p));
                }
            }
        }
        best.map(|(e, g, _)| (e, g))
    }

    /// The exception that preempts now, if any.
    pub fn preempting(&self, primask: bool, basepri: u32, faultmask: bool) -> Option<usize> {
        let (e, g) = self.highest_pending()?;
        (g < self.execution_priority(primask, basepri, faultmask)).then_some(e)
    }

    pub fn set_pending(&mut self, e: usize) {
        self.pending[e] = true;
    }

    pub fn pend_irq(&mut self, irq: usize) {
        self.pending[16 + irq] = true;
    }

    /// Exception `e` is taken: active, no longer pending.
    pub fn activate(&mut self, e: usize) {
        self.pending[e] = false;
        self.active[e] = true;
        self.nesting.push(e);
    }

    /// The innermost active exception returns.
    pub fn deactivate(&mut self) -> Option<usize> {
        let e = self.nesting.pop()?;
        self.active[e] = false;
        Some(e)
    }

    pub fn current(&self) -> usize {
        self.nesting.last().copied().unwrap_or(0)
    }

    /// Read a system control space register at offset `off` from 0xE000E000.
    pub fn read(&mut self, off: u32, size: usize, now: u64) -> Result<u32, Unknown> {
        if (0x400..0x400 + IRQS as u32).contains(&off) {
            // NVIC_IPR: byte-accessible priority bytes.
            let mut v = 0;
            for i in 0..size as u32 {
                let irq = (off - 0x400 + i) as usize;
                v |= u32::from(self.prio.get(16 + irq).copied().unwrap_or(0)) << (8 * i);
            }
            return Ok(v);
        }
        if (0xD18..0xD24).contains(&off) {
            let mut v = 0;
            for i in 0..size as u32 {
                let e = (off - 0xD14 + i) as usize;
                v |= u32::from(self.prio[e]) << (8 * i);
            }
            return Ok(v);
        }
        if size != 4 {
            return Err(Unknown);
        }
        let bits = |f: &dyn Fn(usize) -> bool, base: u32| -> u32 {
            let word = ((off - base) / 4) as usize;
            (0..32)
                .filter(|b| {
                    let irq = word * 32 + b;
                    irq < IRQS && f(16 + irq)
                })
                .fold(0, |v, b| v | 1 << b)
        };
        Ok(match off {
            // ICTR: 64 interrupt lines implemented.
            0x004 => 1,
            0x010..=0x01C => self.systick.read(off, now),
            0x100..=0x104 => bits(&|e| self.enabled[e], 0x100),
            0x180..=0x184 => bits(&|e| self.enabled[e], 0x180),
            0x200..=0x204 => bits(&|e| self.pending[e], 0x200),
            0x280..=0x284 => bits(&|e| self.pending[e], 0x280),
            0x300..=0x304 => bits(&|e| self.active[e], 0x300),
            // CPUID: Cortex-M3 r1p1.
            0xD00 => 0x411F_C231,
            0xD04 => self.icsr(),
            0xD08 => self.vtor,
            0xD0C => 0xFA05_0000 | (self.aircr_prigroup << 8),
            0xD10 => self.scr,
            0xD14 => self.ccr,
            0xD24 => {
                let a = |e: usize, b: u32| if self.active[e] { 1 << b } else { 0 };
                a(4, 0)
                    | a(5, 1)
                    | a(6, 3)
                    | a(SVCALL, 7)
                    | a(12, 8)
                    | a(PENDSV, 10)
                    | a(SYSTICK, 11)
            }
            0xD28 => self.cfsr,
            0xD2C => self.hfsr,
            0xD30 | 0xD34 | 0xD38 | 0xD3C => 0,
            _ => return Err(Unknown),
        })
    }

    fn icsr(&self) -> u32 {
        let pending = self.highest_pending().map_or(0, |(e, _)| e as u32);
        let isr_pending = (16..EXC_COUNT).any(|e| self.pending[e]);
        let ret_to_base = self.nesting.len() <= 1;
        (self.current() as u32)
            | (u32::from(ret_to_base) << 11)
            | (pending << 12)
            | (u32::from(isr_pending) << 22)
            | (u32::from(self.pending[SYSTICK]) << 26)
            | (u32::from(self.pending[PENDSV]) << 28)
            | (u32::from(self.pending[2]) << 31)
    }

    /// Write a system control space register.
    pub fn write(
        &mut self,
        off: u32,
        size: usize,
        v: u32,
        now: u64,
        core_hz: u32,
    ) -> Result<(), Unknown> {
        if (0x400..0x400 + IRQS as u32).contains(&off) {
            for i in 0..size as u32 {
                let irq = (off - 0x400 + i) as usize;
                if let Some(p) = self.prio.get_mut(16 + irq) {
                    *p = (v >> (8 * i)) as u8 & PRIO_MASK;
                }
            }
            return Ok(());
        }
        if (0xD18..0xD24).contains(&off) {
            for i in 0..size as u32 {
                let e = (off - 0xD14 + i) as usize;
                if e >= 4 {
                    self.prio[e] = (v >> (8 * i)) as u8 & PRIO_MASK;
                }
            }
            return Ok(());
        }
        if size != 4 {
            return Err(Unknown);
        }
        let mut each = |base: u32, f: &mut dyn FnMut(&mut Self, usize)| {
            let word = ((off - base) / 4) as usize;
            for b in 0..32 {
                let irq = word * 32 + b;
                if irq < IRQS && v & (1 << b) != 0 {
                    f(self, 16 + irq);
                }
            }
        };
        match off {
            0x010..=0x01C => self.systick.write(off, v, now, core_hz),
            0x100..=0x104 => each(0x100, &mut |n, e| n.enabled[e] = true),
            0x180..=0x184 => each(0x180, &mut |n, e| n.enabled[e] = false),
            0x200..=0x204 => each(0x200, &mut |n, e| n.pending[e] = true),
            0x280..=0x284 => each(0x280, &mut |n, e| n.pending[e] = false),
            0xD04 => {
                if v & (1 << 31) != 0 {
                    self.pending[2] = true;
                }
                if v & (1 << 28) != 0 {
                    self.pending[PENDSV] = true;
                }
                if v & (1 << 27) != 0 {
                    self.pending[PENDSV] = false;
                }
                if v & (1 << 26) != 0 {
                    self.pending[SYSTICK] = true;
                }
                if v & (1 << 25) != 0 {
                    self.pending[SYSTICK] = false;
                }
            }
            0xD08 => self.vtor = v & 0x3FFF_FF80,
            0xD0C => {
                // Writes without the key are ignored (B3.2.6).
                if v >> 16 == 0x05FA {
                    self.aircr_prigroup = (v >> 8) & 7;
                    if v & (1 << 2) != 0 {
                        self.reset_requested = true;
                    }
                }
            }
            0xD10 => self.scr = v & 0x16,
            0xD14 => self.ccr = v & 0x31B,
            0xD24 => {}
            0xD28 => self.cfsr &= !v,
            0xD2C => self.hfsr &= !v,
            // STIR: software trigger.
            0xF00 => {
                let irq = (v & 0x1FF) as usize;
                if irq < IRQS {
                    self.pending[16 + irq] = true;
                }
            }
            _ => return Err(Unknown),
        }
        Ok(())
    }

    /// Bring SysTick up to `now`, pending its exception on each wrap to 0.
    pub fn advance(&mut self, now: u64, core_hz: u32) {
        if self.systick.advance(now, core_hz) {
            self.pending[SYSTICK] = true;
        }
    }
}

impl Default for Nvic {
    fn default() -> Self {
        Self::new()
    }
}

/// SysTick (B3.3): a 24-bit down counter on the core clock (CLKSOURCE = 1) or the
/// core clock / 8 (the STM32's external reference); it reloads from LOAD on the clock
/// after reaching 0, and reaching 0 sets COUNTFLAG and pends SysTick when TICKINT is set.
pub struct SysTick {
    ctrl: u32,
    load: u32,
    /// The counter value at `since` (valid while enabled).
    val: u32,
    since: u64,
    /// Time units per counter tick, fixed when the counter is enabled.
    tick_t: u64,
}

impl SysTick {
    fn new() -> SysTick {
        SysTick {
            ctrl: 0,
            load: 0,
            val: 0,
            since: 0,
            tick_t: 1,
        }
    }

    fn enabled(&self) -> bool {
        self.ctrl & 1 != 0
    }

    /// (value, zeros reached) after `k` ticks from `val`.
    fn after(&self, k: u64) -> (u32, u64) {
        let v0 = u64::from(self.val);
        let period = u64::from(self.load) + 1;
        if k <= v0 {
            return (self.val - k as u32, u64::from(k == v0 && k > 0));
        }
        let beyond = k - v0 - 1;
        let value = self.load as u64 - beyond % period;
        // Zero reached at v0 (if v0 > 0), then every period.
        let zeros = u64::from(v0 > 0) + if self.load == 0 { 0 } else { (k - v0) / period };
        (value as u32, zeros)
    }

    /// Ticks until the counter next reaches 0 (from `since`).
    fn ticks_to_zero(&self) -> Option<u64> {
        if !self.enabled() || self.load == 0 && self.val == 0 {
            return None;
        }
        Some(if self.val > 0 {
            u64::from(self.val)
        } else {
            u64::from(self.load) + 1
        })
    }

    /// The next time the counter reaches 0 with TICKINT set.
    pub fn next_event(&self) -> Option<u64> {
        if self.ctrl & 2 == 0 {
            return None;
        }
        self.ticks_to_zero().map(|k| self.since + k * self.tick_t)
    }

    fn sync(&mut self, now: u64) -> u64 {
        if !self.enabled() {
            self.since = now;
            return 0;
        }
        let k = (now - self.since) / self.tick_t;
        let (v, zeros) = self.after(k);
        self.val = v;
        self.since += k * self.tick_t;
        if zeros > 0 {
            self.ctrl |= 1 << 16;
        }
        zeros
    }

    /// Bring the counter to `now`; true when it reached 0 with TICKINT set.
    fn advance(&mut self, now: u64, core_hz: u32) -> bool {
        let zeros = self.sync(now);
        self.set_clock(core_hz);
        zeros > 0 && self.ctrl & 2 != 0
    }

    /// The tick from CLKSOURCE: the core clock, or the external reference (the STM32's
    /// HCLK / 8). Call after bringing the counter to now with the old tick.
    fn set_clock(&mut self, core_hz: u32) {
        let hz = if self.ctrl & 4 != 0 {
            core_hz
        } else {
            core_hz / 8
        };
        self.tick_t = t_per_cycle(hz.max(1));
    }

    fn read(&mut self, off: u32, now: u64) -> u32 {
        self.sync(now);
        match off {
            0x10 => {
                let v = self.ctrl;
                self.ctrl &= !(1 << 16);
                v
            }
            0x14 => self.load,
            0x18 => self.val,
            // CALIB (PM0056 4.5.4): 9000, the reload for 1 ms at HCLK/8 = 9 MHz.
            _ => 9000,
        }
    }

    fn write(&mut self, off: u32, v: u32, now: u64, core_hz: u32) {
        self.sync(now);
        match off {
            0x10 => {
                if !self.enabled() && v & 1 != 0 {
                    self.since = now;
                }
                self.ctrl = (self.ctrl & (1 << 16)) | (v & 7);
                self.set_clock(core_hz);
            }
            0x14 => self.load = v & 0x00FF_FFFF,
            0x18 => {
                self.val = 0;
                self.ctrl &= !(1 << 16);
                self.since = now;
            }
            _ => {}
        }
    }
}

/// Time units of `n` cycles at 72 MHz.
pub const fn cycles72(n: u64) -> u64 {
    n * T_PER_US / 72
}
