//! The core's debug blocks that a program uses without a debugger attached: DEMCR's
//! TRCENA (ARMv7-M C1.6.5) and the DWT cycle counter (C1.8.6). The counter counts
//! core clock cycles of the cycle model while TRCENA and CYCCNTENA are both set; it
//! wraps at 32 bits and may be written. The DWT's other counters, comparators and
//! the lock access registers are not modelled (an access stops the run).

use crate::clock::t_per_cycle;

/// DWT_CTRL's read-only part on the Cortex-M3: four comparators (NUMCOMP) and every
/// optional counter present (the NO* bits clear).
const CTRL_ID: u32 = 4 << 28;
const CYCCNTENA: u32 = 1;
const TRCENA: u32 = 1 << 24;

#[derive(Default)]
pub struct Debug {
    demcr: u32,
    dwt_ctrl: u32,
    /// CYCCNT at `since` (while counting).
    cyccnt: u32,
    since: u64,
    /// Time units per core cycle when counting started.
    cycle_t: u64,
}

impl Debug {
    fn counting(&self) -> bool {
        self.demcr & TRCENA != 0 && self.dwt_ctrl & CYCCNTENA != 0
    }

    fn cycles_at(&self, now: u64) -> u32 {
        if !self.counting() {
            return self.cyccnt;
        }
        let n = (now - self.since) / self.cycle_t;
        self.cyccnt.wrapping_add(n as u32)
    }

    /// Freeze the count at `now` before a change of what it depends on (the
    /// registers, or the core clock: the board calls this when the clocks change).
    pub fn sync(&mut self, now: u64, core_hz: u32) {
        self.cyccnt = self.cycles_at(now);
        self.since = now;
        self.cycle_t = t_per_cycle(core_hz);
    }

    pub fn read_demcr(&self) -> u32 {
        self.demcr
    }

    pub fn write_demcr(&mut self, v: u32, now: u64, core_hz: u32) {
        self.sync(now, core_hz);
        // TRCENA, MON_* and the vector-catch bits are plain storage here.
        self.demcr = v & 0x010F_07F1;
    }

    /// A DWT register at offset `off` from 0xE0001000.
    pub fn read_dwt(&self, off: u32, now: u64) -> Option<u32> {
        match off {
            0x000 => Some(CTRL_ID | self.dwt_ctrl),
            0x004 => Some(self.cycles_at(now)),
            _ => None,
        }
    }

    pub fn write_dwt(&mut self, off: u32, v: u32, now: u64, core_hz: u32) -> Option<()> {
        self.sync(now, core_hz);
        match off {
            // Only CYCCNTENA is modelled among the writable bits.
            0x000 => self.dwt_ctrl = v & CYCCNTENA,
            0x004 => self.cyccnt = v,
            _ => return None,
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::T_PER_US;

    #[test]
    fn counts_core_cycles_only_with_trcena_and_cyccntena() {
        let hz = 72_000_000;
        let mut d = Debug::default();
        d.write_dwt(0, 1, 0, hz).unwrap();
        assert_eq!(d.read_dwt(4, 10 * T_PER_US), Some(0), "TRCENA off");
        d.write_demcr(TRCENA, 10 * T_PER_US, hz);
        assert_eq!(d.read_dwt(4, 11 * T_PER_US), Some(72));
        d.write_dwt(4, u32::MAX, 11 * T_PER_US, hz).unwrap();
        assert_eq!(d.read_dwt(4, 11 * T_PER_US + 4), Some(1), "wraps");
        d.write_dwt(0, 0, 12 * T_PER_US, hz).unwrap();
        // u32::MAX + 72 cycles, then stopped.
        assert_eq!(d.read_dwt(4, 20 * T_PER_US), Some(71), "stopped");
        assert_eq!(d.read_dwt(0, 0), Some(0x4000_0000));
    }
}
