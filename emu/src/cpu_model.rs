//! The cycle model of the STM32F103's Cortex-M3 (emu/README.md, "Cycle model"): what
//! each instruction, bus access and exception costs, in CPU cycles. It owns only the
//! arithmetic; `machine.rs` applies it per translated block.
//!
//! Shaped as a static cost per instruction (decoded once per block from its Thumb-2
//! encoding, Cortex-M3 TRM r1p1 Table 3.1) plus what only the run knows: whether the
//! block's last branch was taken (pipeline refill, and the flash's wait states when
//! the target is in flash), data reads from flash (wait states), and APB register
//! accesses (the AHB-to-APB bridge). Two modes: `Typical` takes the middle of each
//! range the TRM gives, `Pessimistic` its upper end, and adds the flash's fetch
//! bandwidth limit on straight 32-bit code; CI runs the timing tests pessimistic.

use std::sync::atomic::{AtomicU8, Ordering};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CpuModel {
    Typical,
    Pessimistic,
}

/// The model new machines use: `--cpu` sets it for the process, else the
/// `INKSTEP_EMU_CPU` environment variable (`typical` or `pessimistic`), else
/// pessimistic.
pub static DEFAULT_CPU_MODEL: AtomicU8 = AtomicU8::new(0);

thread_local! {
    static THREAD_MODEL: std::cell::Cell<Option<CpuModel>> = const { std::cell::Cell::new(None) };
}

impl CpuModel {
    pub fn name(self) -> &'static str {
        match self {
            CpuModel::Typical => "typical",
            CpuModel::Pessimistic => "pessimistic",
        }
    }

    pub fn parse(s: &str) -> Option<CpuModel> {
        match s {
            "typical" => Some(CpuModel::Typical),
            "pessimistic" => Some(CpuModel::Pessimistic),
            _ => None,
        }
    }

    pub fn set_default(m: CpuModel) {
        DEFAULT_CPU_MODEL.store(1 + m as u8, Ordering::Relaxed);
    }

    /// Pin the model of machines this thread creates (a test that states why it
    /// runs under another model than the process's).
    pub fn set_for_thread(m: CpuModel) {
        THREAD_MODEL.with(|t| t.set(Some(m)));
    }

    pub fn default_model() -> CpuModel {
        if let Some(m) = THREAD_MODEL.with(|t| t.get()) {
            return m;
        }
        match DEFAULT_CPU_MODEL.load(Ordering::Relaxed) {
            1 => CpuModel::Typical,
            2 => CpuModel::Pessimistic,
            _ => std::env::var("INKSTEP_EMU_CPU")
                .ok()
                .and_then(|s| CpuModel::parse(&s))
                .unwrap_or(CpuModel::Pessimistic),
        }
    }

    fn pess(self) -> bool {
        self == CpuModel::Pessimistic
    }

    /// Pipeline refill after a taken branch (TRM Table 3.1's P, 1 to 3 cycles). A
    /// short conditional branch measured on an F103 from SRAM costs 1 + 2.
    pub fn refill(self) -> u32 {
        if self.pess() {
            3
        } else {
            2
        }
    }

    /// Exception entry (TRM 5.5.1: 12 cycles with zero wait states) with the vector
    /// read and the handler's first fetch from flash; pessimistic: both pay the wait
    /// states in full, none overlapped with the stacking.
    pub fn entry(self, ws: u32) -> u32 {
        12 + if self.pess() { 2 * ws } else { ws }
    }

    /// Exception return (12 cycles) with the refill at the return address in flash.
    pub fn exit(self, ws: u32) -> u32 {
        12 + if self.pess() { 2 * ws } else { ws }
    }

    /// Tail-chaining (6 cycles) with the vector read and the refill.
    pub fn tail_chain(self, ws: u32) -> u32 {
        6 + if self.pess() { 2 * ws } else { ws }
    }

    /// A data read from flash (a literal pool, a constant table): the wait states,
    /// plus one cycle of contention with the instruction fetch when pessimistic.
    pub fn flash_read(self, ws: u32) -> u32 {
        if ws == 0 {
            0
        } else if self.pess() {
            ws + 1
        } else {
            ws
        }
    }

    /// Extra cycles of a peripheral register access through the AHB-to-APB bridge
    /// (RM0008 3.1: APB1 at 36 MHz, APB2 at 72 MHz), by address. Typical: reads wait
    /// for the bus (two APB clocks and one for the bridge), writes are buffered and
    /// pay one. Pessimistic: a write waits like a read (a full write buffer).
    pub fn apb_access(
        self,
        addr: u32,
        write: bool,
        hclk_per_pclk1: u32,
        hclk_per_pclk2: u32,
    ) -> u32 {
        let ratio = match addr {
            0x4000_0000..=0x4000_FFFF => hclk_per_pclk1,
            0x4001_0000..=0x4001_FFFF => hclk_per_pclk2,
            _ => return 0,
        };
        let read = 2 * ratio + 1;
        match (write, self.pess()) {
            (false, _) | (true, true) => read,
            (true, false) => 1,
        }
    }
}

/// The static costs of one translated block, decoded once.
#[derive(Clone, Debug, Default)]
pub struct BlockCost {
    /// Cycles after each instruction, cumulated, with the last one's branch not taken.
    pub cum: Vec<u32>,
    /// Extra cycles when the last instruction's branch is taken, not counting the
    /// flash wait states at the target (added by the run, which knows the target).
    pub taken: u32,
    /// The last instruction writes the PC (a branch of any kind).
    pub branches: bool,
    /// Cycles the flash needs to deliver the block's code (its 64-bit lines at
    /// 1 + wait states each): pessimistic mode charges the block at least this.
    pub fetch_floor: u32,
}

impl BlockCost {
    pub fn n(&self) -> u32 {
        self.cum.len() as u32
    }

    /// Cycles of the first `k` instructions (`k` = n: the whole block, not taken).
    pub fn upto(&self, k: u32) -> u32 {
        if k == 0 {
            0
        } else {
            self.cum[(k as usize).min(self.cum.len()) - 1]
        }
    }
}

/// Instruction length from the first halfword (Thumb-2: 0b11101, 0b11110 and 0b11111
/// in the top bits start a 32-bit instruction).
pub fn instr_len(halfword: u16) -> u32 {
    if halfword >> 11 >= 0b11101 {
        4
    } else {
        2
    }
}

/// What an instruction is, for its cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Cycles, fixed.
    Alu(u32),
    /// A single load or store (pipelines with a neighbouring one).
    LoadStore,
    /// LDM/STM/PUSH/POP (and LDRD/STRD): 1 + registers.
    Multiple(u32),
    /// A conditional branch: 1 cycle not taken, 1 + P taken.
    CondBranch,
    /// Writes the PC always: `base` cycles + P.
    Branch(u32),
    /// IT: folded onto a preceding 16-bit instruction (typical) or 1 cycle.
    It,
}

fn classify16(h: u16) -> Kind {
    match h >> 12 {
        0x0..=0x3 => Kind::Alu(1),
        0x4 => {
            if h & 0xF800 == 0x4800 {
                Kind::LoadStore // LDR literal
            } else if h & 0xFF00 == 0x4700 {
                Kind::Branch(1) // BX / BLX
            } else if h & 0xFC00 == 0x4400 && (h >> 8) & 3 != 1 {
                // ADD / MOV high registers: a branch when Rd is the PC.
                let rd = ((h >> 4) & 8) | (h & 7);
                if rd == 15 && (h >> 8) & 3 != 1 {
                    Kind::Branch(1)
                } else {
                    Kind::Alu(1)
                }
            } else {
                Kind::Alu(1)
            }
        }
        0x5..=0x9 => Kind::LoadStore,
        0xA => Kind::Alu(1),
        0xB => {
            if h & 0xF500 == 0xB100 {
                Kind::CondBranch // CBZ / CBNZ
            } else if h & 0xFE00 == 0xB400 {
                Kind::Multiple(((h & 0xFF).count_ones() + u32::from(h >> 8 & 1)).max(1))
            } else if h & 0xFE00 == 0xBC00 {
                let regs = (h & 0xFF).count_ones();
                if h & 0x100 != 0 {
                    Kind::Branch(1 + regs + 1) // POP {.., pc}: 1 + N, then P
                } else {
                    Kind::Multiple(regs.max(1))
                }
            } else if h & 0xFF00 == 0xBF00 && h & 0xF != 0 {
                Kind::It
            } else if h & 0xFFE8 == 0xB660 {
                Kind::Alu(2) // CPSIE / CPSID (TRM: 1 or 2; 2 here, they are rare)
            } else {
                Kind::Alu(1)
            }
        }
        0xC => Kind::Multiple((h & 0xFF).count_ones().max(1)),
        0xD => {
            if (h >> 8) & 0xF >= 0xE {
                Kind::Alu(1) // UDF, SVC
            } else {
                Kind::CondBranch
            }
        }
        _ => Kind::Branch(1), // B (T2)
    }
}

fn classify32(h1: u16, h2: u16, m: CpuModel) -> Kind {
    let pess = m == CpuModel::Pessimistic;
    let op1 = (h1 >> 11) & 3;
    match op1 {
        0b01 => {
            if h1 & 0xFE40 == 0xE800 {
                // LDM / STM (T2): 1 + N; a load into the PC branches.
                let regs = (h2.count_ones()).max(1);
                if h1 & 0x10 != 0 && h2 & 0x8000 != 0 {
                    Kind::Branch(1 + regs)
                } else {
                    Kind::Multiple(regs)
                }
            } else if h1 & 0xFE40 == 0xE840 {
                if h1 & 0xFFF0 == 0xE8D0 && h2 & 0xFFE0 == 0xF000 {
                    Kind::Branch(2) // TBB / TBH: a load, then the branch
                } else if h1 & 0x0120 != 0 {
                    Kind::Multiple(2) // LDRD / STRD
                } else {
                    Kind::Alu(2) // LDREX / STREX
                }
            } else {
                Kind::Alu(1) // data processing (shifted register), coprocessor
            }
        }
        0b10 => {
            if h2 & 0x8000 == 0 {
                Kind::Alu(1) // data processing (immediates)
            } else {
                let op = (h2 >> 12) & 7;
                if op & 0b101 == 0b000 {
                    if (h1 >> 7) & 7 != 7 {
                        Kind::CondBranch // B<c>.W
                    } else if h1 & 0xFFF0 == 0xF3B0 {
                        Kind::Alu(if pess { 4 } else { 2 }) // DSB / DMB / ISB: 1 + B
                    } else {
                        Kind::Alu(2) // MSR / MRS / hints
                    }
                } else {
                    Kind::Branch(1) // B.W, BL
                }
            }
        }
        _ => {
            // 0b11: loads and stores, data processing (register), multiplies.
            if h1 & 0xFE00 == 0xF800 {
                // Single load/store; a load into the PC branches.
                let load = h1 & 0x10 != 0;
                if load && (h2 >> 12) == 15 && h1 & 0x60 == 0x40 {
                    Kind::Branch(2)
                } else {
                    Kind::LoadStore
                }
            } else if h1 & 0xFF80 == 0xFB00 {
                // MUL (Ra = PC) 1, MLA / MLS 2.
                if (h2 >> 12) == 15 && (h2 >> 4) & 0xF == 0 {
                    Kind::Alu(1)
                } else {
                    Kind::Alu(2)
                }
            } else if h1 & 0xFF80 == 0xFB80 {
                match (h1 >> 4) & 7 {
                    // SDIV / UDIV: 2 to 12 (early termination on the operands).
                    0b001 | 0b011 => Kind::Alu(if pess { 12 } else { 7 }),
                    // SMULL / UMULL: 3 to 5.
                    0b000 | 0b010 => Kind::Alu(if pess { 5 } else { 4 }),
                    // SMLAL / UMLAL: 4 to 7.
                    _ => Kind::Alu(if pess { 7 } else { 5 }),
                }
            } else {
                Kind::Alu(1)
            }
        }
    }
}

/// The costs of the block of Thumb-2 `code` at `addr`.
pub fn block_cost(code: &[u8], addr: u32, m: CpuModel, ws: u32) -> BlockCost {
    let pess = m == CpuModel::Pessimistic;
    let mut cum = Vec::new();
    let mut total = 0u32;
    let mut i = 0usize;
    let mut prev_ls = false;
    let mut prev_16 = false;
    let mut taken = 0;
    let mut branches = false;
    while i + 1 < code.len() {
        let h1 = u16::from_le_bytes([code[i], code[i + 1]]);
        let len = instr_len(h1) as usize;
        let kind = if len == 4 && i + 3 < code.len() {
            classify32(h1, u16::from_le_bytes([code[i + 2], code[i + 3]]), m)
        } else {
            classify16(h1)
        };
        let c = match kind {
            Kind::Alu(c) => c,
            // TRM: 2 cycles; neighbouring single loads and stores pipeline their
            // address and data phases, so one right after another takes 1.
            Kind::LoadStore => {
                if prev_ls && !pess {
                    1
                } else {
                    2
                }
            }
            Kind::Multiple(n) => 1 + n,
            Kind::CondBranch => 1,
            Kind::Branch(b) => b,
            Kind::It => u32::from(pess || !prev_16),
        };
        branches = matches!(kind, Kind::CondBranch | Kind::Branch(_));
        taken = match kind {
            Kind::CondBranch | Kind::Branch(_) => m.refill(),
            _ => 0,
        };
        prev_ls = kind == Kind::LoadStore;
        prev_16 = len == 2;
        total += c;
        cum.push(total);
        i += len;
    }
    // The flash interface reads 64-bit lines, each in 1 + ws cycles.
    let first = addr & !7;
    let end = addr + code.len() as u32;
    let lines = (end + 7 - first) / 8;
    BlockCost {
        cum,
        taken,
        branches,
        fetch_floor: lines * (1 + ws),
    }
}

/// The whole block's cycles: `next` is where the CPU went after it (None: unknown,
/// e.g. an exception return), `to_flash` whether that address is in flash.
pub fn block_total(
    b: &BlockCost,
    fallthrough: u32,
    next: Option<u32>,
    m: CpuModel,
    ws: u32,
) -> u32 {
    let mut c = b.upto(b.n());
    if let Some(next) = next {
        if b.branches && next != fallthrough && next < 0xFFFF_FF00 {
            c += b.taken;
            if in_flash(next) {
                c += ws;
                // A 32-bit target straddling two 64-bit lines needs both.
                if m == CpuModel::Pessimistic && next & 7 == 6 {
                    c += 1 + ws;
                }
            }
        }
    }
    if m == CpuModel::Pessimistic && in_flash(fallthrough) {
        c = c.max(b.fetch_floor);
    }
    c
}

/// Code and data in the flash (and its alias at 0).
pub fn in_flash(addr: u32) -> bool {
    addr < 0x0002_0000 || (0x0800_0000..0x0802_0000).contains(&addr)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn asm(hw: &[u16]) -> Vec<u8> {
        hw.iter().flat_map(|h| h.to_le_bytes()).collect()
    }

    /// The loop `ldr r3, [sp]; adds r3, #1; str r3, [sp]; cmp r3, r2; bne` (a
    /// volatile counter), at 0x0800_1000 in flash with 2 wait states: TRM costs
    /// 2 + 1 + 2 + 1 + (1 + P) plus 2 for the refill from flash.
    #[test]
    fn counter_loop_in_flash() {
        let code = asm(&[0x9B00, 0x3301, 0x9300, 0x4293, 0xD1FA]);
        let a = 0x0800_1000;
        let t = block_cost(&code, a, CpuModel::Typical, 2);
        let p = block_cost(&code, a, CpuModel::Pessimistic, 2);
        assert_eq!(block_total(&t, a + 10, Some(a), CpuModel::Typical, 2), 11);
        assert_eq!(
            block_total(&p, a + 10, Some(a), CpuModel::Pessimistic, 2),
            12
        );
        // Not taken: the branch costs one cycle.
        assert_eq!(
            block_total(&t, a + 10, Some(a + 10), CpuModel::Typical, 2),
            7
        );
    }

    /// `subs r0, #1; cmp r0, #0; bne` in flash: measured at 6 cycles a turn on
    /// STM32F103ZET6 and VET6 at 72 MHz (MarlinFirmware/Marlin pull request 19059).
    #[test]
    fn marlin_delay_loop_in_flash() {
        let code = asm(&[0x3801, 0x2800, 0xD1FC]);
        let a = 0x0800_2000;
        let t = block_cost(&code, a, CpuModel::Typical, 2);
        let p = block_cost(&code, a, CpuModel::Pessimistic, 2);
        assert_eq!(block_total(&t, a + 6, Some(a), CpuModel::Typical, 2), 7);
        assert_eq!(block_total(&p, a + 6, Some(a), CpuModel::Pessimistic, 2), 8);
    }

    #[test]
    fn push_pop_divide_and_literal() {
        // push {r4-r7, lr}: 1 + 5; udiv r0, r0, r1: 7 / 12; pop {r4-r7, pc}: 1 + 5 + P.
        let code = asm(&[0xB5F0, 0xFBB0, 0xF0F1, 0xBDF0]);
        let t = block_cost(&code, 0x2000_0000, CpuModel::Typical, 0);
        assert_eq!(t.cum, vec![6, 13, 19]);
        assert_eq!(
            block_total(&t, 0x2000_0008, Some(0x0800_0100), CpuModel::Typical, 2),
            19 + 2 + 2
        );
        let p = block_cost(&code, 0x2000_0000, CpuModel::Pessimistic, 0);
        assert_eq!(p.cum, vec![6, 18, 24]);
        // ldr r0, [pc, #4]; ldr r1, [r0]: pipelined in typical mode.
        let t = block_cost(&asm(&[0x4801, 0x6801]), 0, CpuModel::Typical, 2);
        assert_eq!(t.cum, vec![2, 3]);
    }

    #[test]
    fn apb_costs() {
        let m = CpuModel::Typical;
        assert_eq!(m.apb_access(0x4000_0000, false, 2, 1), 5); // TIM2 read, APB1
        assert_eq!(m.apb_access(0x4001_0800, false, 2, 1), 3); // GPIOA read, APB2
        assert_eq!(m.apb_access(0x4001_0810, true, 2, 1), 1);
        assert_eq!(CpuModel::Pessimistic.apb_access(0x4001_0810, true, 2, 1), 3);
        assert_eq!(m.apb_access(0x4002_1000, false, 2, 1), 0); // RCC on the AHB
    }
}
