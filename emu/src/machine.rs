//! The emulated STM32F103CB: the unicorn Cortex-M3 CPU with the board's memory map,
//! the ARMv7-M exception model done here (unicorn has no NVIC: stacking, EXC_RETURN,
//! tail-chaining, late arrival, fault escalation), the cycle model, and the run loop.
//!
//! Cycle model (emu/README.md, `cpu_model.rs`): each instruction costs its Cortex-M3
//! cycles (TRM Table 3.1) with the flash's wait states after taken branches and on
//! data reads from flash, APB accesses their bridge cycles, exceptions their entry,
//! return and tail-chain cycles, in a typical or a pessimistic mode; flash programming stalls the CPU for the operation's time; WFI sleeps until the
//! next event. Time advances per translated block (a straight run of instructions):
//! interrupts are taken at block boundaries, peripherals (timers, SPI, USB) have
//! their own exact times.

use crate::board::{Board, Halt, FLASH_BASE};
use crate::clock::{t_per_cycle, us};
use crate::cpu_model::{block_cost, block_total, instr_len, BlockCost, CpuModel};
use crate::elf::Image;
use crate::nvic::{HARDFAULT, SVCALL};
use crate::periph::flash::{Flash, SIZE as FLASH_SIZE};
use crate::periph::BusError;
use crate::profiler::Profiler;
use crate::rtt::{self, Log};
use std::collections::HashMap;
use unicorn_engine::unicorn_const::{uc_error, Arch, HookType, Mode, Prot};
use unicorn_engine::{ArmCpuModel, RegisterARM, Unicorn};

pub const RAM_BASE: u32 = 0x2000_0000;
pub const RAM_SIZE: u32 = 20 * 1024;
const SCS_BASE: u64 = 0xE000_0000;

/// Why a run stopped before its time was up.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Stop {
    /// An access no model answers (the message names the register), at this PC.
    Bus { message: String, pc: u32 },
    /// A semihosting exit (defmt-test's end) with this status.
    Exit(i32),
    /// A BKPT outside semihosting: a debugger would halt here.
    Breakpoint { pc: u32, in_hardfault: bool },
    /// A fault while in HardFault: the core locks up.
    Lockup { pc: u32 },
    /// The power was cut at a flash operation.
    PowerCut,
    /// HardFault was entered with the vector catch on (`State::catch_hardfault`), as
    /// a debug probe halts there; the PC is where the fault happened.
    HardFault { pc: u32 },
    /// The CPU failed in a way the model does not cover.
    Cpu { message: String, pc: u32 },
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Bus { message, pc } => write!(f, "{message} (PC 0x{pc:08X})"),
            Stop::Exit(s) => write!(f, "semihosting exit with status {s}"),
            Stop::Breakpoint { pc, in_hardfault } => {
                write!(
                    f,
                    "breakpoint at PC 0x{pc:08X}{}",
                    if *in_hardfault { " in HardFault" } else { "" }
                )
            }
            Stop::Lockup { pc } => write!(f, "lockup: a fault in HardFault (PC 0x{pc:08X})"),
            Stop::PowerCut => write!(f, "power cut at a flash operation"),
            Stop::HardFault { pc } => write!(f, "HardFault (caught) at PC 0x{pc:08X}"),
            Stop::Cpu { message, pc } => write!(f, "{message} (PC 0x{pc:08X})"),
        }
    }
}

/// Per-exception time, for CPU load figures.
#[derive(Clone, Debug, Default)]
pub struct Profile {
    /// Time units spent in each exception (exclusive of what preempted it); index 0
    /// is thread mode (init and idle).
    pub busy: Vec<u64>,
    /// Entries of each exception.
    pub entries: Vec<u64>,
    /// Time asleep in WFI.
    pub sleep: u64,
    /// Exception entries whose handler began with SP not 8-byte aligned (CCR.STKALIGN
    /// clear and SP at 4 mod 8): compiled code assumes an 8-byte aligned stack
    /// (AAPCS), so such a handler may address its locals wrongly.
    pub misaligned_entries: u64,
}

/// Everything the hooks reach: the board and the CPU-side bookkeeping.
pub struct State {
    pub board: Board,
    /// Translated blocks' costs (`costs`), by (address, size, flash wait states).
    blocks: HashMap<(u64, u32, u32), u32>,
    costs: Vec<BlockCost>,
    /// The cycle model's mode.
    pub model: CpuModel,
    /// Stop the CPU at the next block boundary.
    stop_requested: bool,
    /// The current run's end.
    until: u64,
    next_event: u64,
    pub stop: Option<Stop>,
    /// The block executing now: its address, its instruction count, and the time it
    /// started. Its time is charged when it has run (at the next block, or when the
    /// run stops), so a block the run stops in front of is never charged.
    block: Block,
    /// How late interrupts were taken (see [`Lateness`]).
    pub lateness: Lateness,
    /// When the exception the run stopped for became due.
    due_at: Option<u64>,
    /// An exception is pending but masked by PRIMASK, BASEPRI or FAULTMASK.
    masked_pending: bool,
    /// The PC of the last bus access (reported with a bus error).
    access_pc: u32,
    pub log: Option<Log>,
    rtt: Option<u32>,
    pub profile: Profile,
    profile_mark: u64,
    /// When recording: (end time, exception) of each stretch of execution.
    pub runs: Option<Vec<(u64, usize)>>,
    pub instructions: u64,
    /// CPU cycles charged to instructions (exception entry and return not counted).
    pub cycles: u64,
    /// Watchdog resets so far.
    pub watchdog_resets: u32,
    pub hardfaults: u32,
    /// The log is echoed to stderr as it is decoded.
    pub echo_log: bool,
    /// Halt at HardFault entry (DEMCR.VC_HARDERR, what probe-rs sets for tests).
    pub catch_hardfault: bool,
    /// Delay-loop iterations skipped at their cycle cost.
    pub delay_loops_skipped: u64,
    /// The CPU branched to this EXC_RETURN value.
    exc_return: Option<u32>,
    /// Read the RTT channel when the CPU reaches this address (a log frame ended).
    drain_at: Option<u32>,
    /// Instructions per function, when asked for (`cargo emu run --profile`).
    pub profiler: Option<Profiler>,
}

pub struct Machine<'a> {
    pub uc: Unicorn<'a, State>,
}

/// The block the CPU is running (see `State::block`).
#[derive(Clone, Copy, Debug, Default)]
struct Block {
    addr: u32,
    size: u32,
    /// Instructions not yet charged (0 once charged).
    n: u32,
    start: u64,
    /// Its costs (an index into `State::costs`) and the wait states they assume.
    cost: u32,
    ws: u32,
    /// Cycles the block stalled so far on bus accesses (APB, flash data).
    stall: u32,
}

/// Interrupts are taken at block boundaries, so one that becomes due inside a block
/// waits for the block's end: this is how long, measured on every event that asked
/// for an exception (emu/README.md, cycle model).
#[derive(Clone, Debug, Default)]
pub struct Lateness {
    /// Events that made an exception preempt.
    pub count: u64,
    /// Sum and maximum of (boundary time - event time), in time units.
    pub total: u64,
    pub max: u64,
    /// The longest block executed, in instructions.
    pub longest_block: u32,
}

/// The IT (If-Then) execution state bits of xPSR (ARMv7-M B1.4.2: ICI/IT).
const IT_BITS: u64 = 0x0600_FC00;

/// The CPU's IT state, in xPSR's bit positions. Unicorn reads EPSR (where the IT bits
/// live) as zero through its XPSR register, as MRS does; its CPSR view has them, at the
/// same positions.
fn it_state(uc: &Unicorn<State>) -> u32 {
    (uc.reg_read(RegisterARM::CPSR).unwrap_or(0) & IT_BITS) as u32
}

/// Sets the CPU's IT state (`bits` in xPSR's positions): a read-modify-write of the
/// CPSR view, which leaves every other field as it was.
fn set_it_state(uc: &mut Unicorn<State>, bits: u32) {
    let c = uc.reg_read(RegisterARM::CPSR).unwrap_or(0);
    let _ = uc.reg_write(
        RegisterARM::CPSR,
        (c & !IT_BITS) | (u64::from(bits) & IT_BITS),
    );
}

/// Clears a stale IT state (see `Machine::mmio_time`), writing only if there is one.
fn clear_it_state(uc: &mut Unicorn<State>) {
    if it_state(uc) != 0 {
        set_it_state(uc, 0);
    }
}

/// Instructions in `code` (Thumb-2: 16- and 32-bit encodings).
fn count_instructions(code: &[u8]) -> u32 {
    let mut n = 0;
    let mut i = 0;
    while i + 1 < code.len() {
        i += instr_len(u16::from_le_bytes([code[i], code[i + 1]])) as usize;
        n += 1;
    }
    n
}

impl<'a> Machine<'a> {
    /// A board with `image` flashed and its flash array in `flash` (kept by the caller
    /// in a file, or blank), held in reset until the first run.
    pub fn new(image: &Image, mut flash: Flash) -> Result<Machine<'a>, String> {
        let in_flash: Vec<(u32, &[u8])> = image
            .segments
            .iter()
            .filter(|(a, _)| (FLASH_BASE..FLASH_BASE + FLASH_SIZE as u32).contains(a))
            .map(|(a, d)| (*a, d.as_slice()))
            .collect();
        flash.load(&in_flash)?;
        let settings = match (
            image.symbol("_settings_start"),
            image.symbol("_settings_end"),
        ) {
            (Some(s), Some(e)) => (s - FLASH_BASE)..(e - FLASH_BASE),
            _ => (FLASH_SIZE as u32)..(FLASH_SIZE as u32),
        };
        if settings.start % 4096 != 0 || settings.end % 4096 != 0 {
            return Err(format!(
                "settings pages 0x{:X}..0x{:X} are not 4 KB aligned (the emulator serves them as one MMIO window)",
                settings.start, settings.end
            ));
        }
        let log = Log::new(&image.bytes).ok();
        let state = State {
            board: Board::new(flash, settings.clone()),
            blocks: HashMap::new(),
            costs: Vec::new(),
            model: CpuModel::default_model(),
            stop_requested: false,
            until: 0,
            next_event: 0,
            stop: None,
            block: Block::default(),
            lateness: Lateness::default(),
            due_at: None,
            masked_pending: false,
            access_pc: 0,
            log,
            rtt: image.symbol("_SEGGER_RTT"),
            profile: Profile {
                busy: vec![0; crate::nvic::EXC_COUNT],
                entries: vec![0; crate::nvic::EXC_COUNT],
                sleep: 0,
                misaligned_entries: 0,
            },
            profile_mark: 0,
            runs: None,
            instructions: 0,
            cycles: 0,
            watchdog_resets: 0,
            hardfaults: 0,
            echo_log: false,
            catch_hardfault: false,
            delay_loops_skipped: 0,
            exc_return: None,
            drain_at: None,
            profiler: None,
        };
        let mut uc = Unicorn::new_with_data(Arch::ARM, Mode::THUMB | Mode::MCLASS, state)
            .map_err(|e| format!("unicorn: {e:?}"))?;
        uc.ctl_set_cpu_model(ArmCpuModel::CORTEX_M3 as i32)
            .map_err(|e| format!("unicorn cpu model: {e:?}"))?;
        let e = |e: uc_error| format!("unicorn map: {e:?}");
        // Program flash below the settings pages: read and execute, written only
        // through the flash controller (copied in when it changes).
        let prog_end = u64::from(settings.start.min(FLASH_SIZE as u32));
        uc.mem_map(u64::from(FLASH_BASE), prog_end, Prot::READ | Prot::EXEC)
            .map_err(e)?;
        if settings.end > settings.start {
            uc.mmio_map(
                u64::from(FLASH_BASE + settings.start),
                u64::from(settings.end - settings.start),
                Some(|uc: &mut Unicorn<State>, off: u64, size: usize| {
                    Machine::mmio_time(uc, 0, false);
                    Machine::flash_data_read(uc);
                    uc.get_data().board.settings_read(off as u32, size) as u64
                }),
                Some(|uc: &mut Unicorn<State>, off: u64, size: usize, v: u64| {
                    Machine::mmio_time(uc, 0, true);
                    let s = uc.get_data_mut();
                    if let Err(err) = s.board.settings_write(off as u32, size, v as u32) {
                        // A flash write the controller refuses is a bus error on the chip.
                        s.board.bus_fault = Some(err.0);
                        s.stop_requested = true;
                    }
                    Machine::mmio_done(uc, Ok(0), 0);
                }),
            )
            .map_err(e)?;
        }
        // The SRAM is the board's (the DMA controller reads and writes it too).
        let sram = uc.get_data().board.sram.as_ptr();
        // SAFETY: the board's SRAM is RAM_SIZE bytes (Board::new) and lives in
        // unicorn's data, so it outlives the mapping (freed after uc_close).
        unsafe { uc.mem_map_ptr(u64::from(RAM_BASE), u64::from(RAM_SIZE), Prot::ALL, sram) }
            .map_err(e)?;
        // Peripherals: APB1, APB2 and AHB up to the CRC unit.
        uc.mmio_map(
            0x4000_0000,
            0x2_4000,
            Some(|uc: &mut Unicorn<State>, off: u64, size: usize| {
                let addr = 0x4000_0000 + off as u32;
                Machine::mmio_time(uc, addr, false);
                let r = uc.get_data_mut().board.read(addr, size);
                Machine::mmio_done(uc, r.map(u64::from), addr)
            }),
            Some(|uc: &mut Unicorn<State>, off: u64, size: usize, v: u64| {
                let addr = 0x4000_0000 + off as u32;
                Machine::mmio_time(uc, addr, true);
                let r = uc.get_data_mut().board.write(addr, size, v as u32);
                Machine::mmio_done(uc, r.map(|()| 0), addr);
            }),
        )
        .map_err(e)?;
        // The bit-band aliases (ARMv7-M A3.7, PM0056 2.2.5): each word of the alias
        // region is one bit of the peripheral or SRAM word below, read or written
        // with a read-modify-write of that word.
        uc.mmio_map(
            0x4200_0000,
            0x24000 * 32,
            Some(|uc: &mut Unicorn<State>, off: u64, _size: usize| {
                let (addr, bit) = bit_band(0x4000_0000, off);
                Machine::mmio_time(uc, addr, false);
                let r = uc.get_data_mut().board.read(addr, 4);
                Machine::mmio_done(uc, r.map(|v| u64::from((v >> bit) & 1)), addr)
            }),
            Some(|uc: &mut Unicorn<State>, off: u64, _size: usize, v: u64| {
                let (addr, bit) = bit_band(0x4000_0000, off);
                Machine::mmio_time(uc, addr, true);
                let b = &mut uc.get_data_mut().board;
                let r = b
                    .read(addr, 4)
                    .and_then(|w| b.write(addr, 4, with_bit(w, bit, v)));
                Machine::mmio_done(uc, r.map(|()| 0), addr);
            }),
        )
        .map_err(e)?;
        uc.mmio_map(
            0x2200_0000,
            u64::from(RAM_SIZE) * 32,
            Some(|uc: &mut Unicorn<State>, off: u64, _size: usize| {
                let (addr, bit) = bit_band(RAM_BASE, off);
                let mut w = [0u8; 4];
                let _ = uc.mem_read(u64::from(addr), &mut w);
                u64::from((u32::from_le_bytes(w) >> bit) & 1)
            }),
            Some(|uc: &mut Unicorn<State>, off: u64, _size: usize, v: u64| {
                let (addr, bit) = bit_band(RAM_BASE, off);
                let mut w = [0u8; 4];
                let _ = uc.mem_read(u64::from(addr), &mut w);
                let x = with_bit(u32::from_le_bytes(w), bit, v);
                let _ = uc.mem_write(u64::from(addr), &x.to_le_bytes());
            }),
        )
        .map_err(e)?;
        // System memory: the flash size register and the unique ID.
        uc.mmio_map(
            0x1FFF_F000,
            0x1000,
            Some(|uc: &mut Unicorn<State>, off: u64, size: usize| {
                Machine::mmio_time(uc, 0, false);
                let addr = 0x1FFF_F000 + off as u32;
                let r = uc.get_data().board.system_read(addr, size);
                Machine::mmio_done(uc, r.map(u64::from), addr)
            }),
            Some(|uc: &mut Unicorn<State>, off: u64, _size: usize, _v: u64| {
                Machine::mmio_time(uc, 0, false);
                let addr = 0x1FFF_F000 + off as u32;
                let r = Err(BusError("write to system memory".into()));
                Machine::mmio_done(uc, r, addr);
            }),
        )
        .map_err(e)?;
        // The private peripheral bus: the DWT (cycle counter) and the system control
        // space (NVIC, SCB, SysTick, DEMCR).
        uc.mmio_map(
            SCS_BASE,
            0xF000,
            Some(|uc: &mut Unicorn<State>, off: u64, size: usize| {
                Machine::mmio_time(uc, 0, false);
                let s = uc.get_data_mut();
                let r = s.board.ppb_read(off as u32, size);
                Machine::mmio_done(uc, r.map(u64::from), SCS_BASE as u32 + off as u32)
            }),
            Some(|uc: &mut Unicorn<State>, off: u64, size: usize, v: u64| {
                Machine::mmio_time(uc, 0, false);
                let s = uc.get_data_mut();
                let r = s.board.ppb_write(off as u32, size, v as u32);
                Machine::mmio_done(uc, r.map(|()| 0), SCS_BASE as u32 + off as u32);
            }),
        )
        .map_err(e)?;
        // With a memory hook on the buses the CPU keeps its PC exact at every access,
        // which `mmio_time` needs (unicorn otherwise only updates it per block).
        let mut buses = vec![
            (0x1FFF_F000u64, 0x1FFF_FFFFu64),
            (0x4000_0000, 0x43FF_FFFF),
            (SCS_BASE, SCS_BASE + 0xEFFF),
        ];
        if settings.end > settings.start {
            let lo = u64::from(FLASH_BASE + settings.start);
            buses.push((lo, u64::from(FLASH_BASE + settings.end) - 1));
        }
        // Data reads from the program flash (literal pools, constant tables) wait for
        // the flash: the cycle model charges its wait states.
        uc.add_mem_hook(
            HookType::MEM_READ,
            u64::from(FLASH_BASE),
            prog_end - 1 + u64::from(FLASH_BASE),
            |uc: &mut Unicorn<State>, _, _, _, _| {
                Machine::flash_data_read(uc);
                true
            },
        )
        .map_err(|e| format!("unicorn hook: {e:?}"))?;
        for (lo, hi) in buses {
            uc.add_mem_hook(
                HookType::MEM_READ | HookType::MEM_WRITE,
                lo,
                hi,
                |_: &mut Unicorn<State>, _, _, _, _| true,
            )
            .map_err(|e| format!("unicorn hook: {e:?}"))?;
        }

        uc.add_block_hook(1, 0, |uc: &mut Unicorn<State>, addr: u64, size: u32| {
            Machine::on_block(uc, addr, size);
        })
        .map_err(|e| format!("unicorn hook: {e:?}"))?;
        uc.add_intr_hook(|uc: &mut Unicorn<State>, intno: u32| {
            Machine::on_interrupt(uc, intno);
        })
        .map_err(|e| format!("unicorn hook: {e:?}"))?;
        if let Some(release) = image.symbol("_defmt_release") {
            let a = u64::from(release & !1);
            // The frame is complete when the release function returns: drain there.
            uc.add_code_hook(a, a, |uc: &mut Unicorn<State>, _: u64, _: u32| {
                let lr = uc.reg_read(RegisterARM::LR).unwrap_or(0) as u32;
                uc.get_data_mut().drain_at = Some(lr & !1);
            })
            .map_err(|e| format!("unicorn hook: {e:?}"))?;
        }
        let mut m = Machine { uc };
        m.sync_flash_all()?;
        m.reset_cpu()?;
        Ok(m)
    }

    pub fn state(&self) -> &State {
        self.uc.get_data()
    }

    pub fn state_mut(&mut self) -> &mut State {
        self.uc.get_data_mut()
    }

    pub fn board(&mut self) -> &mut Board {
        &mut self.uc.get_data_mut().board
    }

    pub fn now(&self) -> u64 {
        self.uc.get_data().board.now
    }

    /// The word at `addr` in the CPU's memory map (RAM or flash; not peripherals).
    pub fn read_u32(&self, addr: u32) -> Option<u32> {
        let mut w = [0u8; 4];
        self.uc.mem_read(u64::from(addr), &mut w).ok()?;
        Some(u32::from_le_bytes(w))
    }

    fn sync_flash_all(&mut self) -> Result<(), String> {
        let end = self.uc.get_data().board.settings.start as usize;
        let end = end.min(FLASH_SIZE);
        let bytes = self.uc.get_data().board.flash.array[..end].to_vec();
        self.uc
            .mem_write(u64::from(FLASH_BASE), &bytes)
            .map_err(|e| format!("flash: {e:?}"))
    }

    /// The core's reset: SP and PC from the vector table, special registers cleared.
    fn reset_cpu(&mut self) -> Result<(), String> {
        let mut v = [0u8; 8];
        self.uc
            .mem_read(u64::from(FLASH_BASE), &mut v)
            .map_err(|e| format!("vector table: {e:?}"))?;
        let sp = u32::from_le_bytes([v[0], v[1], v[2], v[3]]);
        let pc = u32::from_le_bytes([v[4], v[5], v[6], v[7]]);
        let uc = &mut self.uc;
        for r in [
            RegisterARM::R0,
            RegisterARM::R1,
            RegisterARM::R2,
            RegisterARM::R3,
            RegisterARM::R4,
            RegisterARM::R5,
            RegisterARM::R6,
            RegisterARM::R7,
            RegisterARM::R8,
            RegisterARM::R9,
            RegisterARM::R10,
            RegisterARM::R11,
            RegisterARM::R12,
        ] {
            let _ = uc.reg_write(r, 0);
        }
        let _ = uc.reg_write(RegisterARM::PRIMASK, 0);
        let _ = uc.reg_write(RegisterARM::BASEPRI, 0);
        let _ = uc.reg_write(RegisterARM::FAULTMASK, 0);
        let _ = uc.reg_write(RegisterARM::CONTROL, 0);
        let _ = uc.reg_write(RegisterARM::LR, 0xFFFF_FFFF);
        uc.reg_write(RegisterARM::SP, u64::from(sp))
            .map_err(|e| format!("{e:?}"))?;
        // Thumb state from bit 0 of the vector.
        let _ = uc.reg_write(RegisterARM::XPSR, 1 << 24);
        uc.reg_write(RegisterARM::PC, u64::from(pc & !1))
            .map_err(|e| format!("{e:?}"))?;
        // The vector table sits at flash (VTOR 0 aliases it; the firmware sets VTOR).
        self.uc.get_data_mut().board.nvic.vtor = FLASH_BASE;
        Ok(())
    }

    /// A system reset (watchdog, SYSRESETREQ): peripherals and core reset, RAM kept.
    pub fn system_reset(&mut self, csr_flag: u32) -> Result<(), String> {
        let s = self.uc.get_data_mut();
        s.board.system_reset(csr_flag);
        s.account(s.board.now);
        self.reset_cpu()
    }

    /// A block is about to run: charge the one before it (it ran to its end), bring
    /// the board to now, and stop in front of this block when something is due (the
    /// run loop then takes the exception before the block runs).
    fn on_block(uc: &mut Unicorn<State>, addr: u64, size: u32) {
        let ws = uc.get_data().board.flash.latency();
        let cost = match uc.get_data().blocks.get(&(addr, size, ws)) {
            Some(&i) => i,
            None => {
                let mut code = vec![0u8; size as usize];
                let _ = uc.mem_read(addr, &mut code);
                let s = uc.get_data_mut();
                let c = block_cost(&code, addr as u32, s.model, ws);
                s.costs.push(c);
                let i = s.costs.len() as u32 - 1;
                s.blocks.insert((addr, size, ws), i);
                i
            }
        };
        let n = uc.get_data().costs[cost as usize].n();
        let s = uc.get_data_mut();
        s.charge_block(None, Some(addr as u32));
        if s.board.now >= s.next_event {
            let due = s.next_event;
            s.events();
            if s.stop_requested {
                s.due_at = Some(s.due_at.map_or(due, |d| d.min(due)));
            }
        }
        if s.masked_pending && !s.stop_requested {
            // An interrupt waits behind BASEPRI or PRIMASK: an `msr` that lowers them
            // touches no bus, so the masks are looked at before every block.
            let (primask, basepri, faultmask) = Machine::masks_of(uc);
            let s = uc.get_data_mut();
            if s.board
                .nvic
                .preempting(primask, basepri, faultmask)
                .is_some()
            {
                s.stop_requested = true;
            }
        }
        let s = uc.get_data_mut();
        if s.stop_requested || s.board.now >= s.until || s.board.halt.is_some() {
            // The block does not run: unicorn stops in front of it.
            let _ = uc.emu_stop();
            return;
        }
        // A busy-wait delay loop (`subs rN, #1; bne .-2`, cortex_m::asm::delay): its
        // remaining iterations are skipped at their exact cycle cost.
        if size == 4 && n == 2 {
            if let Some(skipped) = Machine::skip_delay_loop(uc, addr, cost, ws) {
                let s = uc.get_data_mut();
                s.delay_loops_skipped += skipped;
                let turn = s.loop_turn_t(cost, addr as u32, ws);
                s.board.now += skipped * turn;
                s.instructions += skipped * 2;
            }
        }
        if uc.get_data().drain_at == Some(addr as u32) {
            uc.get_data_mut().drain_at = None;
            Machine::drain_rtt(uc);
        }
        if uc.get_data().profiler.is_some() {
            let lr = uc.reg_read(RegisterARM::LR).unwrap_or(0) as u32;
            let s = uc.get_data_mut();
            let exc = s.board.nvic.current();
            if let Some(p) = s.profiler.as_mut() {
                p.block(exc, addr as u32, n, lr);
            }
        }
        let s = uc.get_data_mut();
        s.block = Block {
            addr: addr as u32,
            size,
            n,
            start: s.board.now,
            cost,
            ws,
            stall: 0,
        };
    }

    /// A bus access by the instruction at the PC (exact: the memory hooks keep it):
    /// the board is brought to the time that instruction completes.
    fn mmio_time(uc: &mut Unicorn<State>, addr: u32, write: bool) {
        let pc = uc.reg_read(RegisterARM::PC).unwrap_or(0) as u32;
        // Bringing the PC up to date also brought back the IT state of the accessing
        // instruction, and unicorn leaves it there: the next block would then run as
        // if inside that IT block (its instructions skipped). The translated block
        // tracks IT itself, and writes the state out if it ends inside an IT block.
        // (Unicorn's XPSR view reads the IT bits as zero: `it_state` reads them.)
        clear_it_state(uc);
        let b = uc.get_data().block;
        let done = if b.n > 0 && pc >= b.addr && pc - b.addr < 4 * b.n {
            let mut code = vec![0u8; (pc - b.addr) as usize + 2];
            let _ = uc.mem_read(u64::from(b.addr), &mut code);
            count_instructions(&code).min(b.n)
        } else {
            0
        };
        let s = uc.get_data_mut();
        s.access_pc = pc;
        // The access waits for the APB bridge; later instructions of the block too.
        let (r1, r2) = s.board.apb_ratios();
        let stall = s.model.apb_access(addr, write, r1, r2);
        s.block.stall += stall;
        let cycles = if b.n > 0 {
            s.costs[b.cost as usize].upto(done)
        } else {
            0
        };
        let t = b.start + u64::from(cycles + b.stall + stall) * s.cycle_t();
        if t > s.board.now {
            s.board.now = t;
            if t >= s.next_event {
                s.events();
            }
        }
    }

    /// A data read from the flash: its wait states stall the block.
    fn flash_data_read(uc: &mut Unicorn<State>) {
        // A memory hook brings back the IT state of the accessing instruction, which
        // unicorn then keeps (see `mmio_time`): clear it.
        clear_it_state(uc);
        let s = uc.get_data_mut();
        let ws = s.board.flash.latency();
        s.block.stall += s.model.flash_read(ws);
    }

    /// After a bus access: a refused one stops the run; one that raised an exception
    /// or changed the board's next event is noted for the next boundary.
    fn mmio_done(uc: &mut Unicorn<State>, r: Result<u64, BusError>, addr: u32) -> u64 {
        let s = uc.get_data_mut();
        let v = match r {
            Ok(v) => v,
            Err(err) => {
                s.bus_stop(err.0, addr);
                let _ = uc.emu_stop();
                return 0;
            }
        };
        // The run stops in front of the next block, never here: with the exact PC a
        // stop inside an instruction's access would run that instruction again.
        s.next_event = s.board.next_event();
        if s.board.halt.is_some() || s.board.stall_until > 0 || s.board.nvic.reset_requested {
            s.stop_requested = true;
        }
        if s.irq_may_preempt_soon() && !s.masked_pending {
            if !s.stop_requested {
                s.due_at = Some(s.board.now);
            }
            s.stop_requested = true;
        }
        v
    }

    /// If the block at `addr` is `subs rN, #1; bne addr`, set rN to 1 (the last
    /// iteration runs) and return the iterations skipped. Only while nothing is due
    /// before the loop would end, so no interrupt is delayed.
    fn skip_delay_loop(uc: &mut Unicorn<State>, addr: u64, cost: u32, ws: u32) -> Option<u64> {
        let mut code = [0u8; 4];
        uc.mem_read(addr, &mut code).ok()?;
        let subs = u16::from_le_bytes([code[0], code[1]]);
        let bne = u16::from_le_bytes([code[2], code[3]]);
        // SUBS Rdn, #1 (T2: 00111 ddd 00000001); BNE to the SUBS: offset -6 -> 0xD1FD.
        if subs & 0xF8FF != 0x3801 || bne != 0xD1FD {
            return None;
        }
        let reg = match (subs >> 8) & 7 {
            0 => RegisterARM::R0,
            1 => RegisterARM::R1,
            2 => RegisterARM::R2,
            3 => RegisterARM::R3,
            4 => RegisterARM::R4,
            5 => RegisterARM::R5,
            6 => RegisterARM::R6,
            _ => RegisterARM::R7,
        };
        let count = uc.reg_read(reg).ok()?;
        if count <= 2 {
            return None;
        }
        let s = uc.get_data();
        let turn = s.loop_turn_t(cost, addr as u32, ws);
        // Iterations that fit before the next event.
        let room = s.next_event.min(s.until).saturating_sub(s.board.now) / turn.max(1);
        let skip = (count - 2).min(room);
        if skip == 0 {
            return None;
        }
        uc.reg_write(reg, count - skip).ok()?;
        Some(skip)
    }

    fn on_interrupt(uc: &mut Unicorn<State>, intno: u32) {
        let pc = uc.reg_read(RegisterARM::PC).unwrap_or(0) as u32;
        // QEMU's exception numbers: 1 UDEF, 2 SWI, 7 BKPT.
        match intno {
            7 => {
                // BKPT #imm: the PC is at the instruction (or just after it).
                let mut at = pc;
                let mut h = [0u8; 2];
                let _ = uc.mem_read(u64::from(at), &mut h);
                if h[1] != 0xBE {
                    at = pc.wrapping_sub(2);
                    let _ = uc.mem_read(u64::from(at), &mut h);
                }
                let imm = h[0];
                if imm == 0xAB {
                    let r0 = uc.reg_read(RegisterARM::R0).unwrap_or(0) as u32;
                    let r1 = uc.reg_read(RegisterARM::R1).unwrap_or(0) as u32;
                    let stop = match r0 {
                        // SYS_EXIT: ADP_Stopped_ApplicationExit is success.
                        0x18 => Stop::Exit(if r1 == 0x2_0026 { 0 } else { 1 }),
                        _ => Stop::Cpu {
                            message: format!("semihosting operation 0x{r0:X} is not modelled"),
                            pc: at,
                        },
                    };
                    uc.get_data_mut().stop = Some(stop);
                } else {
                    let in_hf = uc.get_data().board.nvic.active[HARDFAULT];
                    uc.get_data_mut().stop = Some(Stop::Breakpoint {
                        pc: at,
                        in_hardfault: in_hf,
                    });
                }
                let _ = uc.reg_write(RegisterARM::PC, u64::from(at));
                let _ = uc.emu_stop();
            }
            2 => {
                // SVC: the PC is already past it; SVCall is pended and taken next.
                uc.get_data_mut().board.nvic.set_pending(SVCALL);
                uc.get_data_mut().stop_requested = true;
                let _ = uc.emu_stop();
            }
            1 => {
                // UDF or an undefined instruction: UsageFault, escalated to HardFault
                // (the configurable faults are disabled).
                let s = uc.get_data_mut();
                s.board.nvic.cfsr |= 1 << 16;
                s.board.nvic.hfsr |= 1 << 30;
                s.board.nvic.set_pending(HARDFAULT);
                s.stop_requested = true;
                let _ = uc.emu_stop();
            }
            8 => {
                // A branch to an EXC_RETURN value: the exception return happens here.
                let s = uc.get_data_mut();
                s.exc_return = Some(pc | 1);
                s.stop_requested = true;
                let _ = uc.emu_stop();
            }
            _ => {
                uc.get_data_mut().stop = Some(Stop::Cpu {
                    message: format!("CPU exception {intno} is not modelled"),
                    pc,
                });
                let _ = uc.emu_stop();
            }
        }
    }

    /// Read what the firmware logged into the RTT up channel.
    fn drain_rtt(uc: &mut Unicorn<State>) {
        let Some(cb) = uc.get_data().rtt else {
            return;
        };
        let mut d = [0u8; 24];
        if uc.mem_read(u64::from(cb + rtt::UP0), &mut d).is_err() {
            return;
        }
        let w = |i: usize| u32::from_le_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        let (buf, size, write, mut read) = (w(4), w(8), w(12), w(16));
        if size == 0 || write >= size || read >= size || write == read {
            return;
        }
        let mut bytes = Vec::new();
        while read != write {
            let end = if write > read { write } else { size };
            let mut chunk = vec![0u8; (end - read) as usize];
            if uc.mem_read(u64::from(buf + read), &mut chunk).is_err() {
                return;
            }
            bytes.extend_from_slice(&chunk);
            read = if end == size { 0 } else { end };
        }
        let _ = uc.mem_write(u64::from(cb + rtt::UP0 + rtt::UP_READ), &read.to_le_bytes());
        let s = uc.get_data_mut();
        let t = us(s.board.now);
        if let Some(log) = &mut s.log {
            log.echo = s.echo_log;
            log.received(&bytes, t);
        }
    }

    /// Run until virtual time `until` (or a stop). Returns the stop, if any.
    pub fn run_until(&mut self, until: u64) -> Option<Stop> {
        loop {
            if let Some(stop) = self.uc.get_data_mut().stop.take() {
                Machine::drain_rtt(&mut self.uc);
                return Some(stop);
            }
            if self.now() >= until {
                Machine::drain_rtt(&mut self.uc);
                return None;
            }
            if let Err(stop) = self.boundary() {
                Machine::drain_rtt(&mut self.uc);
                return Some(stop);
            }
            if self.uc.get_data().stop.is_some() {
                continue;
            }
            let s = self.uc.get_data_mut();
            s.until = until;
            s.stop_requested = false;
            s.next_event = s.board.next_event();
            let pc = self.uc.reg_read(RegisterARM::PC).unwrap_or(0);
            let r = self.uc.emu_start(pc | 1, 0, 0, 0);
            self.charge_stopped_block(&r);
            if let Err(stop) = self.after_run(r) {
                Machine::drain_rtt(&mut self.uc);
                return Some(stop);
            }
        }
    }

    /// At a block boundary: halts, resets, stalls, bus faults, and exceptions to take.
    fn boundary(&mut self) -> Result<(), Stop> {
        let pc = self.uc.reg_read(RegisterARM::PC).unwrap_or(0) as u32;
        // Flash the controller changed: into the CPU's view.
        let dirty = std::mem::take(&mut self.uc.get_data_mut().board.flash_dirty);
        for (at, len) in dirty {
            if at < self.uc.get_data().board.settings.start as usize {
                let bytes = self.uc.get_data().board.flash.array[at..at + len].to_vec();
                let _ = self.uc.mem_write(u64::from(FLASH_BASE) + at as u64, &bytes);
                let _ = self.uc.ctl_remove_cache(
                    u64::from(FLASH_BASE) + at as u64,
                    u64::from(FLASH_BASE) + (at + len) as u64,
                );
            }
        }
        let s = self.uc.get_data_mut();
        match s.board.halt.take() {
            Some(Halt::Bus(e)) => return Err(Stop::Bus { message: e.0, pc }),
            Some(Halt::PowerCut) => return Err(Stop::PowerCut),
            None => {}
        }
        if s.board.stall_until > s.board.now {
            let t = s.board.stall_until;
            s.board.now = t;
        }
        s.board.stall_until = 0;
        let now = s.board.now;
        s.events_at(now);
        if s.board.nvic.reset_requested {
            s.board.nvic.reset_requested = false;
            // RCC_CSR SFTRSTF.
            self.system_reset(1 << 28)
                .map_err(|m| Stop::Cpu { message: m, pc })?;
        }
        if self.uc.get_data().watchdog_fired() {
            self.uc.get_data_mut().watchdog_resets += 1;
            // RCC_CSR IWDGRSTF.
            self.system_reset(1 << 29)
                .map_err(|m| Stop::Cpu { message: m, pc })?;
        }
        if let Some(msg) = self.uc.get_data_mut().board.bus_fault.take() {
            // A bus error answer: BusFault, escalated to HardFault.
            let _ = msg;
            self.fault(pc)?;
        }
        self.take_pending()
    }

    /// Take the most urgent pending exception if it preempts.
    fn take_pending(&mut self) -> Result<(), Stop> {
        let (primask, basepri, faultmask) = self.masks();
        let s = self.uc.get_data_mut();
        let due = s.due_at.take();
        let taken = s.board.nvic.preempting(primask, basepri, faultmask);
        // Pending and enabled, but held back by a mask: watched at every block.
        s.masked_pending = taken.is_none() && s.irq_may_preempt_soon();
        if let Some(e) = taken {
            if let Some(due) = due {
                let late = s.board.now.saturating_sub(due);
                let l = &mut s.lateness;
                l.count += 1;
                l.total += late;
                l.max = l.max.max(late);
            }
            self.enter(e)?;
        }
        Ok(())
    }

    fn masks(&self) -> (bool, u32, bool) {
        Machine::masks_of(&self.uc)
    }

    /// PRIMASK, BASEPRI and FAULTMASK.
    fn masks_of(uc: &Unicorn<State>) -> (bool, u32, bool) {
        let r = |reg| uc.reg_read(reg).unwrap_or(0);
        (
            r(RegisterARM::PRIMASK) & 1 != 0,
            r(RegisterARM::BASEPRI) as u32,
            r(RegisterARM::FAULTMASK) & 1 != 0,
        )
    }

    fn reg(&self, r: RegisterARM) -> u32 {
        self.uc.reg_read(r).unwrap_or(0) as u32
    }

    /// Exception entry (ARMv7-M B1.5.6): the 8-word frame on the main stack (aligned
    /// to 8 bytes when CCR.STKALIGN is set), EXC_RETURN in LR, the vector in PC.
    fn enter(&mut self, e: usize) -> Result<(), Stop> {
        let pc = self.reg(RegisterARM::PC);
        if e == HARDFAULT && self.uc.get_data().catch_hardfault {
            return Err(Stop::HardFault { pc });
        }
        let s = self.uc.get_data();
        let current = s.board.nvic.current() as u32;
        let stkalign = s.board.nvic.ccr & (1 << 9) != 0;
        let vtor = s.board.nvic.vtor;
        let mut sp = self.reg(RegisterARM::SP);
        // The frame's xPSR: flags, the interrupted IT state (an exception may come
        // between the instructions of an IT block: its rest runs after the return) and
        // the Thumb bit, which unicorn's XPSR view reads as zero.
        let it = it_state(&self.uc);
        let mut xpsr =
            (self.reg(RegisterARM::XPSR) & !0x1FF & !(IT_BITS as u32)) | it | 1 << 24 | current;
        if stkalign && sp & 4 != 0 {
            sp -= 4;
            xpsr |= 1 << 9;
        }
        sp -= 32;
        let frame = [
            self.reg(RegisterARM::R0),
            self.reg(RegisterARM::R1),
            self.reg(RegisterARM::R2),
            self.reg(RegisterARM::R3),
            self.reg(RegisterARM::R12),
            self.reg(RegisterARM::LR),
            pc,
            xpsr,
        ];
        let bytes: Vec<u8> = frame.iter().flat_map(|w| w.to_le_bytes()).collect();
        if self.uc.mem_write(u64::from(sp), &bytes).is_err() {
            // A stacking fault: outside RAM the push fails (MSTKERR / STKERR).
            return self.stacking_fault(pc, e);
        }
        let _ = self.uc.reg_write(RegisterARM::SP, u64::from(sp));
        if sp & 7 != 0 {
            self.uc.get_data_mut().profile.misaligned_entries += 1;
        }
        let exc_return: u32 = if current == 0 {
            0xFFFF_FFF9
        } else {
            0xFFFF_FFF1
        };
        let _ = self.uc.reg_write(RegisterARM::LR, u64::from(exc_return));
        // Stacking takes the entry time; the board goes on meanwhile. Late arrival
        // (ARMv7-M B1.5.4, Cortex-M3 TRM 5.5.2): an exception more urgent than `e`
        // that becomes pending before the vector is fetched is taken instead, on the
        // same frame; `e` stays pending and follows by tail-chaining.
        let s = self.uc.get_data_mut();
        let cost = u64::from(s.model.entry(s.board.flash.latency())) * s.cycle_t();
        let start = s.board.now;
        s.account(start);
        s.events_at(start + cost);
        let nvic = &s.board.nvic;
        let e = match nvic.highest_pending() {
            Some((late, g)) if g < nvic.group_priority(e) => late,
            _ => e,
        };
        s.board.nvic.activate(e);
        s.profile.entries[e] += 1;
        s.profile.busy[e] += s.board.now - start;
        s.profile_mark = s.board.now;
        self.vector(e, vtor, pc)
    }

    fn stacking_fault(&mut self, pc: u32, e: usize) -> Result<(), Stop> {
        if e == HARDFAULT || self.uc.get_data().board.nvic.active[HARDFAULT] {
            return Err(Stop::Lockup { pc });
        }
        Err(Stop::Cpu {
            message: format!("stack overflow: exception {e} could not be stacked"),
            pc,
        })
    }

    fn vector(&mut self, e: usize, vtor: u32, pc: u32) -> Result<(), Stop> {
        let mut v = [0u8; 4];
        self.uc
            .mem_read(u64::from(vtor + 4 * e as u32), &mut v)
            .map_err(|_| Stop::Cpu {
                message: format!("vector {e} unreadable"),
                pc,
            })?;
        let handler = u32::from_le_bytes(v) & !1;
        let _ = self.uc.reg_write(RegisterARM::PC, u64::from(handler));
        // The handler starts outside any IT block, in Thumb state, with IPSR = its
        // exception number (B1.5.6).
        let x = self.reg(RegisterARM::XPSR) & !(IT_BITS as u32) & !0x1FF;
        let _ = self
            .uc
            .reg_write(RegisterARM::XPSR, u64::from(x | 1 << 24 | e as u32));
        set_it_state(&mut self.uc, 0);
        Ok(())
    }

    /// Exception return through EXC_RETURN `exc`: tail-chain into a pending exception
    /// that preempts what would be returned to, or unstack the frame.
    fn exception_return(&mut self, exc: u32) -> Result<(), Stop> {
        let pc = exc;
        if exc & 0xF == 0xD || exc & 0xFFFF_FFF0 != 0xFFFF_FFF0 {
            return Err(Stop::Cpu {
                message: format!("EXC_RETURN 0x{exc:08X} (process stack) is not modelled"),
                pc,
            });
        }
        let s = self.uc.get_data_mut();
        // The handler's time up to here is its own (charged before it stops being the
        // active exception).
        s.account(s.board.now);
        if s.board.nvic.deactivate().is_none() {
            return Err(Stop::Cpu {
                message: "exception return in thread mode".into(),
                pc,
            });
        }
        let (primask, basepri, faultmask) = self.masks();
        let s = self.uc.get_data();
        if let Some(e) = s.board.nvic.preempting(primask, basepri, faultmask) {
            // Tail-chain: the frame stays, LR keeps the same EXC_RETURN.
            let vtor = s.board.nvic.vtor;
            self.vector(e, vtor, pc)?;
            let _ = self.uc.reg_write(RegisterARM::LR, u64::from(exc));
            let s = self.uc.get_data_mut();
            let cost = u64::from(s.model.tail_chain(s.board.flash.latency())) * s.cycle_t();
            s.switch_to(e, cost);
            return Ok(());
        }
        let sp = self.reg(RegisterARM::SP);
        let mut f = [0u8; 32];
        self.uc
            .mem_read(u64::from(sp), &mut f)
            .map_err(|_| Stop::Cpu {
                message: "unstacking outside RAM".into(),
                pc,
            })?;
        let w = |i: usize| u32::from_le_bytes([f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]]);
        let regs = [
            RegisterARM::R0,
            RegisterARM::R1,
            RegisterARM::R2,
            RegisterARM::R3,
            RegisterARM::R12,
            RegisterARM::LR,
        ];
        for (i, r) in regs.into_iter().enumerate() {
            let _ = self.uc.reg_write(r, u64::from(w(i)));
        }
        let xpsr = w(7);
        let sp = sp + 32 + if xpsr & (1 << 9) != 0 { 4 } else { 0 };
        let _ = self.uc.reg_write(RegisterARM::SP, u64::from(sp));
        let _ = self.uc.reg_write(RegisterARM::XPSR, u64::from(xpsr));
        // The IT state goes back too: the rest of an interrupted IT block runs as
        // conditionally as it would have (unicorn's XPSR write sets the flags only).
        set_it_state(&mut self.uc, xpsr & IT_BITS as u32);
        let _ = self.uc.reg_write(RegisterARM::PC, u64::from(w(6) & !1));
        let s = self.uc.get_data_mut();
        let back = s.board.nvic.current();
        let cost = u64::from(s.model.exit(s.board.flash.latency())) * s.cycle_t();
        s.switch_to(back, cost);
        Ok(())
    }

    /// A fault at `pc`: HardFault (forced), or lockup when already in HardFault.
    fn fault(&mut self, pc: u32) -> Result<(), Stop> {
        let s = self.uc.get_data_mut();
        if s.board.nvic.active[HARDFAULT] {
            return Err(Stop::Lockup { pc });
        }
        s.hardfaults += 1;
        eprintln!(
            "emu: HardFault at PC 0x{pc:08X}, {:.3} ms",
            us(s.board.now) / 1000.0
        );
        s.board.nvic.hfsr |= 1 << 30;
        s.board.nvic.cfsr |= 1 << 8;
        s.board.nvic.set_pending(HARDFAULT);
        self.enter(HARDFAULT)
    }

    /// The run stopped: the block it stopped in ran to its end, unless an instruction
    /// faulted (then the instructions before it ran) or trapped (BKPT, SVC, UDF: up to
    /// and including it).
    fn charge_stopped_block(&mut self, r: &Result<(), uc_error>) {
        let pc = self.reg(RegisterARM::PC);
        let b = self.uc.get_data().block;
        let inside = b.n > 0 && pc >= b.addr && pc - b.addr < 4 * b.n;
        let partial = match r {
            Err(
                uc_error::READ_UNMAPPED
                | uc_error::WRITE_UNMAPPED
                | uc_error::FETCH_PROT
                | uc_error::WRITE_PROT
                | uc_error::READ_PROT
                | uc_error::INSN_INVALID,
            ) if inside => {
                let mut code = vec![0u8; (pc - b.addr) as usize];
                let _ = self.uc.mem_read(u64::from(b.addr), &mut code);
                Some(count_instructions(&code) + u32::from(*r == Err(uc_error::INSN_INVALID)))
            }
            _ => None,
        };
        self.uc.get_data_mut().charge_block(partial, Some(pc));
    }

    /// After `emu_start` returned: exception returns, faults, WFI.
    fn after_run(&mut self, r: Result<(), uc_error>) -> Result<(), Stop> {
        let pc = self.reg(RegisterARM::PC);
        if let Some(exc) = self.uc.get_data_mut().exc_return.take() {
            return self.exception_return(exc);
        }
        match r {
            Ok(()) => {
                if self.uc.get_data().stop_requested || self.uc.get_data().stop.is_some() {
                    return Ok(());
                }
                // WFI halts unicorn: sleep until the next event unless an interrupt
                // can be taken now.
                let mut h = [0u8; 2];
                let _ = self.uc.mem_read(u64::from(pc.wrapping_sub(2)), &mut h);
                if u16::from_le_bytes(h) == 0xBF30 {
                    self.sleep();
                }
                Ok(())
            }
            Err(uc_error::FETCH_UNMAPPED) if pc >= 0xFFFF_FFF0 => self.exception_return(pc | 1),
            Err(
                uc_error::READ_UNMAPPED
                | uc_error::WRITE_UNMAPPED
                | uc_error::FETCH_UNMAPPED
                | uc_error::FETCH_PROT
                | uc_error::WRITE_PROT
                | uc_error::READ_PROT,
            ) => {
                if self.uc.get_data().stop.is_some() {
                    return Ok(());
                }
                self.fault(pc)
            }
            Err(uc_error::INSN_INVALID) => {
                let s = self.uc.get_data_mut();
                s.board.nvic.cfsr |= 1 << 16;
                self.fault(pc)
            }
            Err(e) => Err(Stop::Cpu {
                message: format!("unicorn: {e:?}"),
                pc,
            }),
        }
    }

    /// WFI: nothing to take now, so time jumps to the next event.
    fn sleep(&mut self) {
        let (primask, basepri, faultmask) = self.masks();
        let s = self.uc.get_data_mut();
        let now = s.board.now;
        s.events_at(now);
        // With PRIMASK set an interrupt still wakes the core (it is then not taken).
        let wake = s.board.nvic.highest_pending().is_some_and(|(_, g)| {
            g < s.board.nvic.execution_priority(false, basepri, faultmask) || primask
        });
        if wake {
            return;
        }
        let t = s.board.next_event().min(s.until).max(now);
        s.account(now);
        s.profile.sleep += t - now;
        s.board.now = t;
        s.profile_mark = t;
        s.events_at(t);
    }
}

impl State {
    /// Charge the block that ran: all its instructions (the CPU then went to `next`,
    /// which tells whether its last branch was taken), or the first `partial`.
    fn charge_block(&mut self, partial: Option<u32>, next: Option<u32>) {
        let b = std::mem::take(&mut self.block);
        if b.n == 0 {
            return;
        }
        let n = partial.unwrap_or(b.n).min(b.n);
        let c = &self.costs[b.cost as usize];
        let cycles = match partial {
            Some(k) => c.upto(k),
            None => block_total(c, b.addr + b.size, next, self.model, b.ws),
        };
        self.instructions += u64::from(n);
        self.cycles += u64::from(cycles + b.stall);
        self.lateness.longest_block = self.lateness.longest_block.max(n);
        let t = b.start + u64::from(cycles + b.stall) * self.cycle_t();
        self.board.now = self.board.now.max(t);
    }

    /// Time units per cycle of the current CPU clock.
    fn cycle_t(&self) -> u64 {
        t_per_cycle(self.board.sysclk_hz())
    }

    /// One turn of the delay loop at `addr` (block `cost`), in time units.
    fn loop_turn_t(&self, cost: u32, addr: u32, ws: u32) -> u64 {
        let c = &self.costs[cost as usize];
        u64::from(block_total(c, addr + 4, Some(addr), self.model, ws)) * self.cycle_t()
    }

    fn bus_stop(&mut self, message: String, addr: u32) {
        self.stop = Some(Stop::Bus {
            message: format!("{message} [address 0x{addr:08X}]"),
            pc: self.access_pc,
        });
        self.stop_requested = true;
    }

    fn watchdog_fired(&self) -> bool {
        self.board
            .iwdg
            .deadline()
            .is_some_and(|d| d <= self.board.now)
    }

    /// Peripheral events due now; request a stop when an exception can be taken.
    fn events(&mut self) {
        let now = self.board.now;
        self.events_at(now);
        let irq = self.irq_may_preempt_soon() && !self.masked_pending;
        if irq || self.watchdog_fired() || self.board.halt.is_some() {
            self.stop_requested = true;
        }
    }

    fn events_at(&mut self, now: u64) {
        self.board.advance(now);
        self.next_event = self.board.next_event();
    }

    /// Something is pending that may preempt: the run loop decides at the boundary.
    fn irq_may_preempt_soon(&self) -> bool {
        let nvic = &self.board.nvic;
        match nvic.highest_pending() {
            Some((_, g)) => g < nvic.execution_priority(false, 0, false),
            None => false,
        }
    }

    /// Time accounting on an exception switch to `e` (0 = thread), plus its cost.
    fn switch_to(&mut self, e: usize, cost: u64) {
        let now = self.board.now;
        self.account(now);
        self.board.now += cost;
        if e != 0 && !self.board.nvic.active[e] {
            self.board.nvic.activate(e);
            self.profile.entries[e] += 1;
        }
        self.profile.busy[e] += cost;
        self.profile_mark = self.board.now;
    }

    /// Charge the time since the last mark to the exception running now.
    fn account(&mut self, now: u64) {
        let cur = self.board.nvic.current();
        if let Some(r) = &mut self.runs {
            if now > self.profile_mark {
                r.push((now, cur));
            }
        }
        self.profile.busy[cur] += now.saturating_sub(self.profile_mark);
        self.profile_mark = now;
    }

    /// The time accounting brought to now (for a report).
    pub fn profile_now(&mut self) -> &Profile {
        let now = self.board.now;
        self.account(now);
        &self.profile
    }
}

/// The word and bit a bit-band alias offset `off` stands for, in the region at `base`
/// (ARMv7-M A3.7: each alias word is one bit, 32 alias bytes per byte of the region).
fn bit_band(base: u32, off: u64) -> (u32, u32) {
    ((base + off as u32 / 32) & !3, (off as u32 / 4) % 32)
}

/// `word` with `bit` set to the lowest bit of `v` (a bit-band alias write).
fn with_bit(word: u32, bit: u32, v: u64) -> u32 {
    if v & 1 != 0 {
        word | 1 << bit
    } else {
        word & !(1 << bit)
    }
}
