//! The Blue Pill board around the CPU: the STM32F103's peripherals on their buses, the
//! pins between them and the outside (switches, keypad, stepper drivers, the LCD), the
//! USB cable with its host, and the step trace read off the pins.
//!
//! Owns the address decoding (RM0008 memory map, table 3): a register of a modelled
//! peripheral goes to its model; a peripheral the board does not model, or a model's
//! unknown register, is a [`BusError`] that stops the run; an address where the chip
//! has nothing is a bus fault (the machine raises HardFault). Peripherals whose clock
//! is off are an error too: on the chip their registers read 0 and ignore writes,
//! which is always a firmware bug.

use crate::clock::t_per_cycle;
#[cfg(test)]
use crate::clock::T_PER_US;
use crate::debug::Debug;
use crate::machine::RAM_SIZE;
use crate::nvic::Nvic;
use crate::periph::dma::{Dma, Item};
use crate::periph::flash::{self, Flash, Op};
use crate::periph::gpio::{exti_irq, Afio, Exti, Port};
use crate::periph::iwdg::Iwdg;
use crate::periph::rcc::Rcc;
use crate::periph::spi::Spi;
use crate::periph::st7920::St7920;
use crate::periph::timer::{Edge, Timer};
use crate::periph::usb::Usb;
use crate::periph::BusError;
use crate::pins::{phase_index, Decode, PosSwitch};
use crate::sram::Sram;
use crate::usb_host::Host;

/// IRQ numbers (RM0008 table 63).
/// DMA1 channel 1; channels 2-7 follow.
pub const IRQ_DMA1_CH1: usize = 11;
pub const IRQ_USB_LP: usize = 20;
pub const IRQ_TIM1_UP: usize = 25;
pub const IRQ_TIM1_CC: usize = 27;
pub const IRQ_TIM2: usize = 28;
pub const IRQ_TIM3: usize = 29;
pub const IRQ_SPI2: usize = 36;

/// DMA1's request lines (RM0008 table 78), as bits of the controller's request mask
/// (bit c: channel c + 1). Channel 5: SPI2's transmit buffer empty.
pub const DMA_SPI2_TX: u32 = 1 << 4;

/// Flash size register value (RM0008 30.1): 128 KB on the STM32F103CB.
pub const F_SIZE_KB: u16 = 128;
/// ... and on the STM32F103C8, whose footprint is the same (`--chip c8`).
pub const F_SIZE_KB_C8: u16 = 64;

/// The F_SIZE that new boards report (the `--chip` option sets it once for the
/// process; a test sets [`Board::f_size_kb`] on its own board instead).
pub static DEFAULT_F_SIZE_KB: std::sync::atomic::AtomicU16 =
    std::sync::atomic::AtomicU16::new(F_SIZE_KB);

/// What the outside drives onto the input pins.
#[derive(Clone, Debug, Default)]
pub struct Outside {
    /// The NC e-stop switch is open (pressed).
    pub estop_open: bool,
    pub limit_x_open: bool,
    pub limit_y_open: bool,
    /// The feed-hold / SYNC input is held low.
    pub feed_hold_low: bool,
    pub cycle_start_low: bool,
    /// Keys held, as (row, column) of the matrix.
    pub keys: Vec<(usize, usize)>,
    /// Limit/home switches at positions (`--switch`): each opens its axis's input
    /// while the axis is beyond it, besides `limit_x_open` / `limit_y_open`.
    pub switches: Vec<PosSwitch>,
}

/// Why the board wants the run to stop.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Halt {
    Bus(BusError),
    PowerCut,
}

/// A step seen on the step pins: the time and the position after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    pub t: u64,
    pub pos: [i32; 3],
}

pub struct Board {
    pub now: u64,
    pub nvic: Nvic,
    pub debug: Debug,
    pub rcc: Rcc,
    pub flash: Flash,
    pub gpio: [Port; 3],
    pub afio: Afio,
    pub exti: Exti,
    pub tim1: Timer,
    pub tim2: Timer,
    /// TIM3: the counter, flags and interrupt; its compare outputs reach no pin.
    pub tim3: Timer,
    pub spi2: Spi,
    pub dma1: Dma,
    /// The SRAM (the CPU's RAM, which the DMA controller reads and writes too).
    pub sram: Sram,
    pub lcd: St7920,
    pub iwdg: Iwdg,
    pub usb: Usb,
    pub host: Host,
    pub outside: Outside,
    /// Where the settings pages are (flash offsets), served through the bus.
    pub settings: std::ops::Range<u32>,
    /// A halt requested by a peripheral.
    pub halt: Option<Halt>,
    /// A precise bus fault from a peripheral access: HardFault at the next boundary.
    pub bus_fault: Option<String>,
    /// The CPU stalls (flash programming) until this time.
    pub stall_until: u64,
    /// Every flash programming stall: (start, duration).
    pub flash_stalls: Vec<(u64, u64)>,
    /// Flash bytes that changed and must be copied into the CPU's view.
    pub flash_dirty: Vec<(usize, usize)>,
    /// Alternate-function output levels of PA0..PA15 (the timers' channels).
    af_a: u32,
    /// Step pins PA0..PA2 and their last levels; the position they produced.
    step_levels: u32,
    pub pos: [i32; 3],
    pub steps: Vec<Step>,
    pub record_steps: bool,
    /// Step rising edges on each axis (counted even when not recording).
    pub step_edges: [u64; 3],
    edges: Vec<Edge>,
    spi_out: Vec<(u64, u16)>,
    lcd_cs: bool,
    /// Pin levels changed since the last look at EXTI and the USB pull-up.
    pins_dirty: bool,
    pub last_irq_lines: u64,
    /// Output pins whose changes by the software are logged (a mask per port).
    pub watch: [u32; 3],
    /// (time, port, pin, new level) of each change of a watched pin.
    pub pin_changes: Vec<(u64, usize, usize, bool)>,
    /// What the flash size register (F_SIZE) reads, KB: the chip (a reset keeps it).
    pub f_size_kb: u16,
    /// How the drivers read the motion pins (the stored settings, re-read after every
    /// flash operation).
    pub decode: Decode,
    /// The half-step sequence index of X's and Y's coils (4-phase): at power-up the
    /// rotor is taken to sit at coil A's position (index 0), where the firmware's
    /// sequence starts; all coils off keeps the index.
    phase: [Option<u8>; 2],
    /// Coil changes that are no half-step (a jump of more than one position).
    pub misreads: u64,
}

impl Board {
    pub fn new(flash: Flash, settings: std::ops::Range<u32>) -> Board {
        let mut b = Board {
            now: 0,
            nvic: Nvic::new(),
            debug: Debug::default(),
            rcc: Rcc::new(),
            flash,
            gpio: [Port::new(), Port::new(), Port::new()],
            afio: Afio::new(),
            exti: Exti::new(),
            tim1: Timer::new("TIM1", true),
            tim2: Timer::new("TIM2", false),
            tim3: Timer::new("TIM3", false),
            spi2: Spi::new("SPI2"),
            dma1: Dma::new(),
            sram: Sram::new(RAM_SIZE as usize),
            lcd: St7920::new(),
            iwdg: Iwdg::new(),
            usb: Usb::new(),
            host: Host::new(),
            outside: Outside::default(),
            settings,
            halt: None,
            bus_fault: None,
            stall_until: 0,
            flash_stalls: Vec::new(),
            flash_dirty: Vec::new(),
            af_a: 0,
            step_levels: 0,
            pos: [0; 3],
            steps: Vec::new(),
            record_steps: true,
            step_edges: [0; 3],
            edges: Vec::new(),
            spi_out: Vec::new(),
            lcd_cs: false,
            pins_dirty: true,
            last_irq_lines: 0,
            watch: [0; 3],
            pin_changes: Vec::new(),
            f_size_kb: DEFAULT_F_SIZE_KB.load(std::sync::atomic::Ordering::Relaxed),
            decode: Decode::default(),
            phase: [Some(0); 2],
            misreads: 0,
        };
        b.read_decode();
        b.clocks_changed();
        b
    }

    /// A system reset (watchdog, AIRCR): every peripheral back to its reset state, the
    /// flash array, the LCD (it has its own supply) and the USB host keep theirs.
    pub fn system_reset(&mut self, csr_flag: u32) {
        self.nvic = Nvic::new();
        self.rcc.reset_keep_flags(csr_flag);
        self.flash.reset();
        self.gpio = [Port::new(), Port::new(), Port::new()];
        self.afio = Afio::new();
        self.exti = Exti::new();
        self.tim1.reset();
        self.tim2.reset();
        self.tim3.reset();
        self.spi2.reset();
        self.dma1.reset();
        self.iwdg = Iwdg::new();
        self.usb = Usb::new();
        self.af_a = 0;
        self.phase = [Some(0); 2];
        self.lcd_cs = false;
        self.pins_dirty = true;
        self.clocks_changed();
        self.pins_changed();
    }

    /// HCLK cycles per PCLK1 and per PCLK2 cycle (the APB prescalers), for the cost
    /// of a register access through the AHB-to-APB bridges.
    pub fn apb_ratios(&self) -> (u32, u32) {
        let h = self.rcc.hclk_hz();
        (
            (h / self.rcc.pclk1_hz().max(1)).max(1),
            (h / self.rcc.pclk2_hz().max(1)).max(1),
        )
    }

    pub fn sysclk_hz(&self) -> u32 {
        self.rcc.sysclk_hz()
    }

    fn clocks_changed(&mut self) {
        self.debug.sync(self.now, self.rcc.hclk_hz());
        self.nvic.advance(self.now, self.rcc.hclk_hz());
        let tim1 = t_per_cycle(self.rcc.tim_apb2_hz());
        let tim2 = t_per_cycle(self.rcc.tim_apb1_hz());
        self.tim1.tick_t = tim1;
        self.tim2.tick_t = tim2;
        self.tim3.tick_t = tim2;
        self.spi2.pclk_t = t_per_cycle(self.rcc.pclk1_hz());
        self.dma1.hclk_t = t_per_cycle(self.rcc.hclk_hz());
    }

    /// The earliest time anything on the board happens by itself.
    pub fn next_event(&self) -> u64 {
        let mut t = self.host.next_event();
        for e in [
            self.nvic.systick.next_event(),
            self.tim1.next_event(),
            self.tim2.next_event(),
            self.tim3.next_event(),
            self.spi2.next_event(),
            self.dma1.next_event(),
            self.iwdg.deadline(),
        ]
        .into_iter()
        .flatten()
        {
            t = t.min(e);
        }
        t
    }

    /// Bring every peripheral to `now`. Returns true when the watchdog fired.
    pub fn advance(&mut self, now: u64) -> bool {
        self.now = self.now.max(now);
        let now = self.now;
        let hclk = self.rcc.hclk_hz();
        self.nvic.advance(now, hclk);
        self.edges.clear();
        let mut edges = std::mem::take(&mut self.edges);
        self.tim1.advance(now, &mut edges);
        self.apply_edges(&edges, true);
        edges.clear();
        self.tim2.advance(now, &mut edges);
        self.apply_edges(&edges, false);
        // TIM3's compare outputs are not wired to pins (enabling one stops the run).
        edges.clear();
        self.tim3.advance(now, &mut edges);
        self.edges = edges;
        self.spi_and_dma(now);
        self.host.advance(now, &mut self.usb);
        if self.pins_dirty {
            self.pins_changed();
        }
        self.update_irqs();
        self.iwdg.deadline().is_some_and(|d| d <= now)
    }

    /// SPI2 and DMA1 up to `now`, event by event in time order: a frame leaving the
    /// shift register empties the transmit buffer, whose DMA request the controller
    /// takes; the byte it moves lands in DR some bus cycles later and shifts out next.
    fn spi_and_dma(&mut self, now: u64) {
        let mut out = std::mem::take(&mut self.spi_out);
        loop {
            let next = [self.spi2.next_event(), self.dma1.next_event()]
                .into_iter()
                .flatten()
                .min();
            let Some(t) = next.filter(|&t| t <= now) else {
                break;
            };
            if self.dma1.next_event() == Some(t) {
                self.dma_move(t);
            }
            out.clear();
            self.spi2.advance(t, &mut out);
            for &(t, frame) in &out {
                if self.lcd_cs {
                    if let Err(e) = self.lcd.byte(t, frame as u8) {
                        self.halt = Some(Halt::Bus(e));
                    }
                }
            }
            self.dma_arbitrate(t);
        }
        self.spi_out = out;
    }

    /// The peripherals' DMA requests (see [`DMA_SPI2_TX`]).
    fn dma_requests(&self) -> u32 {
        let mut r = 0;
        if self.spi2.tx_dma_request() {
            r |= DMA_SPI2_TX;
        }
        r
    }

    /// DMA1 takes a pending request at `t` if its bus is free.
    fn dma_arbitrate(&mut self, t: u64) {
        let requests = self.dma_requests();
        if requests == 0 {
            return;
        }
        let (r1, r2) = self.apb_ratios();
        self.dma1
            .arbitrate(requests, t, |item| dma_cycles(item, r1, r2));
    }

    /// The transfer on DMA1's bus lands at `t`: the read and the write, as the CPU's
    /// would be, at that time (the CPU executes meanwhile and is not charged).
    fn dma_move(&mut self, t: u64) {
        let Some(item) = self.dma1.landed(t) else {
            return;
        };
        let now = std::mem::replace(&mut self.now, t);
        // A narrower destination takes the low bytes, a wider one is zero-padded
        // (RM0008 table 76).
        let moved = match self.dma_read(item.from, item.from_size) {
            Ok(Some(v)) => {
                let v = if item.to_size < 4 {
                    v & ((1u32 << (8 * item.to_size)) - 1)
                } else {
                    v
                };
                self.dma_write(item.to, item.to_size, v)
            }
            Ok(None) => Ok(false),
            Err(e) => Err(e),
        };
        self.now = now;
        match moved {
            Ok(ok) => self.dma1.done(ok),
            Err(e) => {
                self.dma1.done(false);
                self.halt = Some(Halt::Bus(e));
            }
        }
    }

    /// A DMA read: Ok(None) where nothing answers (the transfer error of 13.3.7), an
    /// error where a model refuses (the run stops, as for the CPU).
    fn dma_read(&mut self, addr: u32, size: usize) -> Result<Option<u32>, BusError> {
        let ram = addr.wrapping_sub(crate::machine::RAM_BASE) as usize;
        let flash = addr.wrapping_sub(FLASH_BASE) as usize;
        Ok(if ram < self.sram.len() {
            self.sram.read(ram, size)
        } else if flash < self.flash.array.len() {
            Some(self.flash.read_array(flash, size))
        } else if (0x4000_0000..0x4002_4000).contains(&addr) {
            Some(self.read(addr, size)?)
        } else {
            None
        })
    }

    /// A DMA write: Ok(false) where nothing answers (flash is read-only to it).
    fn dma_write(&mut self, addr: u32, size: usize, v: u32) -> Result<bool, BusError> {
        let ram = addr.wrapping_sub(crate::machine::RAM_BASE) as usize;
        if ram < self.sram.len() {
            return Ok(self.sram.write(ram, size, v).is_some());
        }
        if (0x4000_0000..0x4002_4000).contains(&addr) {
            self.write(addr, size, v)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// Timer output edges onto the pins, in time order (TIM1 CH1 = PA8; TIM2 CH1-4 =
    /// PA0-PA3, no remap).
    fn apply_edges(&mut self, edges: &[Edge], tim1: bool) {
        for e in edges {
            let pin = if tim1 {
                if e.channel != 0 {
                    continue;
                }
                8
            } else {
                e.channel
            };
            let watched = self.watch[0] & (1 << pin) != 0;
            let before = if watched { self.pin(0, pin) } else { false };
            if e.level {
                self.af_a |= 1 << pin;
            } else {
                self.af_a &= !(1 << pin);
            }
            if watched {
                let after = self.pin(0, pin);
                if after != before {
                    self.pin_changes.push((e.t, 0, pin, after));
                }
            }
            if pin < 3 {
                self.watch_steps(e.t);
            }
        }
    }

    /// The level of pin `n` of port `p` (0 = A).
    pub fn pin(&self, p: usize, n: usize) -> bool {
        let af = p == 0 && self.af_a & (1 << n) != 0;
        self.gpio[p].level(n, self.outside_level(p, n), af)
    }

    fn watched_levels(&self, p: usize) -> u32 {
        let mut v = 0;
        let mut w = self.watch[p];
        while w != 0 {
            let n = w.trailing_zeros() as usize;
            w &= w - 1;
            if self.pin(p, n) {
                v |= 1 << n;
            }
        }
        v
    }

    fn log_pin_changes(&mut self, p: usize, before: u32) {
        let mut changed = (before ^ self.watched_levels(p)) & self.watch[p];
        while changed != 0 {
            let n = changed.trailing_zeros() as usize;
            changed &= changed - 1;
            self.pin_changes
                .push((self.now, p, n, before & (1 << n) == 0));
        }
    }

    /// What the outside drives onto pin `n` of port `p` (None: nothing, so a pull
    /// resistor or the floating input decides).
    fn outside_level(&self, p: usize, n: usize) -> Option<bool> {
        let o = &self.outside;
        let nc = |open: bool| if open { None } else { Some(false) };
        match (p, n) {
            (1, 0) => nc(o.estop_open),
            (1, 1) => nc(o.limit_x_open || self.switch_open(0)),
            (1, 3) => nc(o.limit_y_open || self.switch_open(1)),
            (1, 4) => o.feed_hold_low.then_some(false),
            (1, 5) => o.cycle_start_low.then_some(false),
            (1, 6..=9) => {
                let row = n - 6;
                let low = o
                    .keys
                    .iter()
                    .any(|&(r, c)| r == row && !self.column_level(c));
                low.then_some(false)
            }
            _ => None,
        }
    }

    /// A keypad column line (PB10, PB11, PA15, PC14; open drain, high when released).
    fn column_level(&self, c: usize) -> bool {
        let (p, n) = match c {
            0 => (1, 10),
            1 => (1, 11),
            2 => (0, 15),
            _ => (2, 14),
        };
        self.gpio[p].level(n, None, false)
    }

    /// Whether a switch at a position holds `axis`'s input open.
    fn switch_open(&self, axis: usize) -> bool {
        self.outside
            .switches
            .iter()
            .any(|sw| sw.axis == axis && sw.open(self.pos[axis], self.decode.steps_per_mm[axis]))
    }

    /// The settings stored in the flash array decide how the pins are read.
    fn read_decode(&mut self) {
        let r = self.settings.start as usize..self.settings.end as usize;
        let d = match self.flash.array.get(r) {
            Some(pages) => Decode::from_pages(pages),
            None => Decode::default(),
        };
        if d != self.decode {
            self.decode = d;
            // What the pins show now is the new idle state, not a step.
            self.step_levels = self.step_pin_levels();
            self.watch_steps(self.now);
        }
    }

    /// The step pins PA0..PA2, active high (after `$2`).
    fn step_pin_levels(&self) -> u32 {
        let mut levels = 0;
        for a in 0..3 {
            if self.pin(0, a) {
                levels |= 1 << a;
            }
        }
        levels ^ u32::from(self.decode.step_invert)
    }

    /// The motion pins to steps. Step/dir: a step of X, Y, Z at the leading edge of a
    /// pulse on PA0..PA2 (rising, or falling for an axis inverted by `$2`), its
    /// direction the level of PA3..PA5 at that moment (high = negative, unless `$3`
    /// inverts the axis). 4-phase: a step each time X's coils (PA0-PA3) or Y's
    /// (PA4-PA7) move one position along the half-step sequence, forward = positive;
    /// all coils off (released) keeps the position.
    fn watch_steps(&mut self, t: u64) {
        let before = self.pos;
        if self.decode.four_phase {
            let port = (0..8)
                .filter(|&n| self.pin(0, n))
                .fold(0u32, |v, n| v | 1 << n);
            for a in 0..2 {
                let coils = (port >> (4 * a)) & 0xF;
                let Some(idx) = phase_index(coils) else {
                    if coils != 0 {
                        self.misreads += 1;
                    }
                    continue;
                };
                if let Some(prev) = self.phase[a] {
                    match idx.wrapping_sub(prev) & 7 {
                        0 => {}
                        1 => self.pos[a] += 1,
                        7 => self.pos[a] -= 1,
                        _ => self.misreads += 1,
                    }
                    if idx != prev {
                        self.step_edges[a] += 1;
                    }
                }
                self.phase[a] = Some(idx);
            }
        } else {
            let levels = self.step_pin_levels();
            let rising = levels & !self.step_levels;
            self.step_levels = levels;
            for a in 0..3 {
                if rising & (1 << a) != 0 {
                    let negative = self.pin(0, 3 + a) != (self.decode.dir_invert & (1 << a) != 0);
                    self.pos[a] += if negative { -1 } else { 1 };
                    self.step_edges[a] += 1;
                }
            }
        }
        if self.pos == before {
            return;
        }
        if !self.outside.switches.is_empty() {
            self.pins_dirty = true;
        }
        if self.record_steps {
            match self.steps.last_mut() {
                Some(last) if last.t == t => last.pos = self.pos,
                _ => self.steps.push(Step { t, pos: self.pos }),
            }
        }
    }

    /// Pin levels may have changed: EXTI edges, the step pins, the USB pull-up.
    pub fn pins_changed(&mut self) {
        self.pins_dirty = false;
        let mut levels = 0;
        for line in 0..16 {
            let port = self.afio.exti_port(line);
            if port < 3 && self.pin(port, line) {
                levels |= 1 << line;
            }
        }
        self.exti.update(levels);
        self.watch_steps(self.now);
        // The fixed pull-up on D+ (PA12) shows the device unless the pin drives low.
        let dp_low = self.gpio[0].is_output(12) && !self.pin(0, 12);
        self.host.set_attached(!dp_low, self.now);
        let cs = self.pin(1, 12);
        if self.lcd_cs && !cs {
            self.lcd.deselect();
        }
        self.lcd_cs = cs;
    }

    /// The outside changed (a switch, a key).
    pub fn set_outside(&mut self, o: Outside) {
        self.outside = o;
        self.pins_changed();
        self.update_irqs();
    }

    /// Peripheral interrupt requests onto the NVIC (level-sensitive: an asserted line
    /// keeps its interrupt pending).
    pub fn update_irqs(&mut self) {
        let mut lines: u64 = 0;
        let mut req = self.exti.requests();
        while req != 0 {
            let line = req.trailing_zeros() as usize;
            req &= req - 1;
            if line < 16 {
                lines |= 1 << exti_irq(line);
            }
        }
        let (up, cc) = self.tim1.irq();
        if up {
            lines |= 1 << IRQ_TIM1_UP;
        }
        if cc {
            lines |= 1 << IRQ_TIM1_CC;
        }
        let (up, cc) = self.tim2.irq();
        if up || cc {
            lines |= 1 << IRQ_TIM2;
        }
        let (up, cc) = self.tim3.irq();
        if up || cc {
            lines |= 1 << IRQ_TIM3;
        }
        if self.spi2.irq() {
            lines |= 1 << IRQ_SPI2;
        }
        for c in 0..crate::periph::dma::CHANNELS {
            if self.dma1.irq(c) {
                lines |= 1 << (IRQ_DMA1_CH1 + c);
            }
        }
        if self.usb.irq() {
            lines |= 1 << IRQ_USB_LP;
        }
        let mut l = lines;
        while l != 0 {
            let irq = l.trailing_zeros() as usize;
            l &= l - 1;
            self.nvic.pend_irq(irq);
        }
        self.last_irq_lines = lines;
    }

    fn clock_on(&self, apb2: bool, bit: u32, name: &str) -> Result<(), BusError> {
        let en = if apb2 {
            self.rcc.apb2enr
        } else {
            self.rcc.apb1enr
        };
        if en & (1 << bit) == 0 {
            return Err(BusError(format!("{name} accessed with its clock off")));
        }
        Ok(())
    }

    fn clock_on_ahb(&self, bit: u32, name: &str) -> Result<(), BusError> {
        if self.rcc.ahbenr & (1 << bit) == 0 {
            return Err(BusError(format!("{name} accessed with its clock off")));
        }
        Ok(())
    }

    /// A peripheral-space read (0x4000_0000..).
    pub fn read(&mut self, addr: u32, size: usize) -> Result<u32, BusError> {
        let now = self.now;
        let off = addr & 0x3FF;
        let v = match addr & !0x3FF {
            0x4000_0000 => {
                self.clock_on(false, 0, "TIM2")?;
                self.tim2.read(off, now)?
            }
            0x4000_0400 => {
                self.clock_on(false, 1, "TIM3")?;
                self.tim3.read(off, now)?
            }
            0x4000_3000 => self.iwdg.read(off, now)?,
            0x4000_3800 => {
                self.clock_on(false, 14, "SPI2")?;
                self.spi2.read(off)?
            }
            0x4000_5C00 => {
                self.clock_on(false, 23, "USB")?;
                self.usb.read(off)?
            }
            0x4000_6000 => {
                self.clock_on(false, 23, "USB packet memory")?;
                self.usb.pma_read(off, size)
            }
            0x4001_0000 => {
                self.clock_on(true, 0, "AFIO")?;
                self.afio.read(off)?
            }
            0x4001_0400 => self.exti.read(off)?,
            0x4001_0800 | 0x4001_0C00 | 0x4001_1000 => {
                let p = ((addr - 0x4001_0800) / 0x400) as usize;
                self.clock_on(true, 2 + p as u32, "GPIO")?;
                let idr = (0..16)
                    .filter(|&n| self.pin(p, n))
                    .fold(0, |v, n| v | 1 << n);
                self.gpio[p].read(off, idr)?
            }
            0x4001_2C00 => {
                self.clock_on(true, 11, "TIM1")?;
                self.tim1.read(off, now)?
            }
            0x4002_0000 => {
                self.clock_on_ahb(0, "DMA1")?;
                self.dma1.read(off)?
            }
            0x4002_1000 => self.rcc.read(off)?,
            0x4002_2000 => self.flash.read_reg(off)?,
            a => return Err(unmodelled(a)),
        };
        Ok(match size {
            1 => (v >> (8 * (addr & 3))) & 0xFF,
            2 => (v >> (8 * (addr & 2))) & 0xFFFF,
            _ => v,
        })
    }

    /// A peripheral-space write.
    pub fn write(&mut self, addr: u32, size: usize, v: u32) -> Result<(), BusError> {
        let now = self.now;
        let off = addr & 0x3FF;
        // Narrow writes to 32-bit registers replicate the data on the APB bus.
        let v = match size {
            1 => (v & 0xFF) * 0x0101_0101,
            2 => (v & 0xFFFF) * 0x0001_0001,
            _ => v,
        };
        let mut edges = std::mem::take(&mut self.edges);
        edges.clear();
        match addr & !0x3FF {
            0x4000_0000 => {
                self.clock_on(false, 0, "TIM2")?;
                self.tim2.write(off, v, now, &mut edges)?;
                self.apply_edges(&edges, false);
            }
            0x4000_0400 => {
                self.clock_on(false, 1, "TIM3")?;
                if off == 0x20 && v & 0x1111 != 0 {
                    return Err(BusError(
                        "TIM3: compare outputs on pins are not modelled".into(),
                    ));
                }
                let mut unused = Vec::new();
                self.tim3.write(off, v, now, &mut unused)?;
            }
            0x4000_3000 => self.iwdg.write(off, v, now)?,
            0x4000_3800 => {
                self.clock_on(false, 14, "SPI2")?;
                self.spi2.write(off, v, now)?;
            }
            0x4000_5C00 => {
                self.clock_on(false, 23, "USB")?;
                let was = self.usb.powered();
                self.usb.write(off, v)?;
                if was != self.usb.powered() {
                    self.pins_dirty = true;
                }
            }
            0x4000_6000 => {
                self.clock_on(false, 23, "USB packet memory")?;
                self.usb.pma_write(off, size, v);
            }
            0x4001_0000 => {
                self.clock_on(true, 0, "AFIO")?;
                self.afio.write(off, v)?;
                self.pins_dirty = true;
            }
            0x4001_0400 => self.exti.write(off, v)?,
            0x4001_0800 | 0x4001_0C00 | 0x4001_1000 => {
                let p = ((addr - 0x4001_0800) / 0x400) as usize;
                self.clock_on(true, 2 + p as u32, "GPIO")?;
                let before = self.watched_levels(p);
                self.gpio[p].write(off, v)?;
                self.pins_dirty = true;
                self.log_pin_changes(p, before);
            }
            0x4001_2C00 => {
                self.clock_on(true, 11, "TIM1")?;
                self.tim1.write(off, v, now, &mut edges)?;
                self.apply_edges(&edges, true);
            }
            0x4002_0000 => {
                self.clock_on_ahb(0, "DMA1")?;
                self.dma1.write(off, v)?;
            }
            0x4002_1000 => {
                self.rcc.write(off, v)?;
                self.clocks_changed();
            }
            0x4002_2000 => {
                let op = self.flash.write_reg(off, v)?;
                self.flash_op(op);
            }
            a => return Err(unmodelled(a)),
        }
        self.edges = edges;
        if self.pins_dirty {
            self.pins_changed();
        }
        // A write may raise a DMA request (TXDMAEN set) or arm a channel for one.
        self.dma_arbitrate(self.now);
        self.update_irqs();
        Ok(())
    }

    fn flash_op(&mut self, op: Op) {
        match op {
            Op::None => {}
            Op::Changed { at, len, stall_t } => {
                self.stall_until = self.now + stall_t;
                self.flash_stalls.push((self.now, stall_t));
                self.flash_dirty.push((at, len));
                self.read_decode();
            }
            Op::PowerCut => self.halt = Some(Halt::PowerCut),
        }
    }

    /// A read of the settings pages (served here so that programming is modelled).
    pub fn settings_read(&self, offset: u32, size: usize) -> u32 {
        self.flash
            .read_array((self.settings.start + offset) as usize, size)
    }

    pub fn settings_write(&mut self, offset: u32, size: usize, v: u32) -> Result<(), BusError> {
        let op = self
            .flash
            .write_array((self.settings.start + offset) as usize, size, v)?;
        self.flash_op(op);
        Ok(())
    }

    /// The private peripheral bus at offset `off` from 0xE000_0000: the DWT, and the
    /// system control space (NVIC, SCB, SysTick, DEMCR).
    pub fn ppb_read(&mut self, off: u32, size: usize) -> Result<u32, BusError> {
        let now = self.now;
        let v = match off {
            0xEDFC if size == 4 => Some(self.debug.read_demcr()),
            0x1000..=0x1FFF if size == 4 => self.debug.read_dwt(off - 0x1000, now),
            0xE000..=0xEFFF => self.nvic.read(off - 0xE000, size, now).ok(),
            _ => None,
        };
        v.ok_or_else(|| ppb_unknown(off, size))
    }

    pub fn ppb_write(&mut self, off: u32, size: usize, v: u32) -> Result<(), BusError> {
        let now = self.now;
        let hz = self.rcc.hclk_hz();
        let ok = match off {
            0xEDFC if size == 4 => {
                self.debug.write_demcr(v, now, hz);
                Some(())
            }
            0x1000..=0x1FFF if size == 4 => self.debug.write_dwt(off - 0x1000, v, now, hz),
            0xE000..=0xEFFF => self.nvic.write(off - 0xE000, size, v, now, hz).ok(),
            _ => None,
        };
        ok.ok_or_else(|| ppb_unknown(off, size))?;
        self.update_irqs();
        Ok(())
    }

    /// System memory (0x1FFF_F000 page): the flash size register and the unique ID.
    pub fn system_read(&self, addr: u32, size: usize) -> Result<u32, BusError> {
        match (addr, size) {
            (0x1FFF_F7E0, 2) => Ok(u32::from(self.f_size_kb)),
            (0x1FFF_F7E8..=0x1FFF_F7F7, _) => Ok(0x494E_4B53),
            _ => Err(BusError(format!(
                "system memory read at 0x{addr:08X} ({size} bytes)"
            ))),
        }
    }
}

/// Bus clocks from a DMA request taken to its item landing: one to arbitrate, then
/// the read and the write, each 1 on the AHB (SRAM, flash, DMA) or the bridge's
/// 2 x HCLK/PCLK + 1 on an APB (as the CPU's read is costed, emu/README.md). An
/// estimate: RM0008 13.3.2 gives the steps, not their cycles.
fn dma_cycles(item: &Item, hclk_per_pclk1: u32, hclk_per_pclk2: u32) -> u64 {
    let access = |addr: u32| match addr {
        0x4000_0000..=0x4000_FFFF => 2 * hclk_per_pclk1 + 1,
        0x4001_0000..=0x4001_FFFF => 2 * hclk_per_pclk2 + 1,
        _ => 1,
    };
    u64::from(1 + access(item.from) + access(item.to))
}

fn ppb_unknown(off: u32, size: usize) -> BusError {
    BusError(format!(
        "private peripheral bus: no register at 0x{:08X} ({size} bytes)",
        0xE000_0000 + off
    ))
}

/// The error for a peripheral-space address: a real peripheral the board does not
/// model, or a hole in the map (RM0008 table 3).
fn unmodelled(base: u32) -> BusError {
    const NAMES: &[(u32, &str)] = &[
        (0x4000_0400, "TIM3"),
        (0x4000_0800, "TIM4"),
        (0x4000_2800, "RTC"),
        (0x4000_2C00, "WWDG"),
        (0x4000_4400, "USART2"),
        (0x4000_4800, "USART3"),
        (0x4000_5400, "I2C1"),
        (0x4000_5800, "I2C2"),
        (0x4000_6400, "bxCAN"),
        (0x4000_6C00, "BKP"),
        (0x4000_7000, "PWR"),
        (0x4001_1400, "GPIOD"),
        (0x4001_1800, "GPIOE"),
        (0x4001_2400, "ADC1"),
        (0x4001_2800, "ADC2"),
        (0x4001_3000, "SPI1"),
        (0x4001_3800, "USART1"),
        (0x4002_3000, "CRC"),
    ];
    match NAMES.iter().find(|(a, _)| *a == base) {
        Some((_, n)) => BusError(format!("{n} (0x{base:08X}) is not modelled")),
        None => BusError(format!("no peripheral at 0x{base:08X}")),
    }
}

pub use flash::BASE as FLASH_BASE;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::periph::dma::{DIR, EN, GIF, HTIF, MINC, TCIE, TCIF};

    const SPI2_DR: u32 = 0x4000_380C;
    const CCR5: u32 = 0x4002_0000 + 0x08 + 0x14 * 4;

    /// A board at the 8 MHz reset clock with SPI2 (master, f_PCLK/256, so one byte
    /// is 256 µs), the ST7920 selected (PB12 high) and DMA1 clocked.
    fn lcd_board() -> Board {
        let mut b = Board::new(Flash::new(None).unwrap(), 0x2_0000..0x2_0000);
        b.write(0x4002_1014, 4, 0x15).unwrap(); // AHBENR: DMA1
        b.write(0x4002_1018, 4, 1 << 3).unwrap(); // APB2ENR: GPIOB
        b.write(0x4002_101C, 4, 1 << 14).unwrap(); // APB1ENR: SPI2
        b.write(0x4001_0C04, 4, 0x4441_4444).unwrap(); // PB12 push-pull output
        b.write(0x4001_0C10, 4, 1 << 12).unwrap(); // CS high
        b.write(0x4000_3800, 4, 0x4 | 0x38 | 0x40 | 0x300).unwrap();
        b
    }

    /// ST7920 serial frames: (RS, byte) each as start byte and two nibble bytes.
    fn frames(items: &[(bool, u8)]) -> Vec<u8> {
        items
            .iter()
            .flat_map(|&(rs, v)| [if rs { 0xFA } else { 0xF8 }, v & 0xF0, v << 4])
            .collect()
    }

    #[test]
    fn spi2_tx_by_dma_channel_5_streams_back_to_back_without_the_cpu() {
        let mut b = lcd_board();
        // Extended set, graphics on, GDRAM row 3 word 2, one word 0xA53C.
        let bytes = frames(&[
            (false, 0x34),
            (false, 0x36),
            (false, 0x83),
            (false, 0x82),
            (true, 0xA5),
            (true, 0x3C),
        ]);
        for (i, &v) in bytes.iter().enumerate() {
            b.sram.write(0x100 + i, 1, u32::from(v)).unwrap();
        }
        b.write(CCR5 + 4, 4, bytes.len() as u32).unwrap();
        b.write(CCR5 + 8, 4, SPI2_DR).unwrap();
        b.write(CCR5 + 12, 4, 0x2000_0100).unwrap();
        b.write(CCR5, 4, EN | DIR | MINC | TCIE).unwrap();
        assert_eq!(b.dma1.next_event(), None, "no request before TXDMAEN");
        let t0 = 1000;
        b.advance(t0);
        b.write(0x4000_3804, 4, 1 << 1).unwrap(); // CR2.TXDMAEN
                                                  // The request is taken at once; the byte lands in DR 5 bus cycles later (SRAM
                                                  // read 1, APB1 write 3 at HCLK = PCLK1, arbitration 1).
        let cycle = t_per_cycle(8_000_000);
        let byte_t = 256 * T_PER_US;
        assert_eq!(b.dma1.next_event(), Some(t0 + 5 * cycle));
        // Half-way: the transfer is still running, no interrupt yet.
        b.advance(t0 + 5 * cycle + 9 * byte_t);
        assert_eq!(b.last_irq_lines & (1 << (IRQ_DMA1_CH1 + 4)), 0);
        assert_eq!(b.read(CCR5 + 4, 4), Ok(bytes.len() as u32 - 10));
        b.advance(t0 + 20_000 * T_PER_US);
        // Every byte reached the LCD, each one frame after the one before.
        assert_eq!(b.lcd.gdram[3][2], 0xA53C);
        assert_eq!(b.lcd.lost, 0);
        assert_eq!(
            b.lcd.last_byte_t,
            t0 + 5 * cycle + bytes.len() as u64 * byte_t
        );
        assert_eq!(b.dma1.moved[4], bytes.len() as u64);
        // Transfer complete: the flag, channel 5's interrupt (IRQ 15), SPI2 idle.
        assert_eq!(b.read(0x4002_0000, 4), Ok((TCIF | HTIF | GIF) << 16));
        assert_ne!(b.last_irq_lines & (1 << 15), 0);
        assert_eq!(b.read(0x4000_3808, 4).map(|sr| sr & 0x82), Ok(0x02)); // TXE, not BSY
        b.write(0x4002_0004, 4, 1 << 16).unwrap(); // CGIF5
        assert_eq!(b.last_irq_lines & (1 << 15), 0);
    }

    #[test]
    fn a_dma_read_where_nothing_answers_is_a_transfer_error() {
        let mut b = lcd_board();
        b.write(CCR5 + 4, 4, 3).unwrap();
        b.write(CCR5 + 8, 4, SPI2_DR).unwrap();
        b.write(CCR5 + 12, 4, 0x3000_0000).unwrap();
        b.write(CCR5, 4, EN | DIR | MINC | (1 << 3)).unwrap();
        b.write(0x4000_3804, 4, 1 << 1).unwrap();
        b.advance(10 * T_PER_US);
        assert_eq!(b.read(0x4002_0000, 4), Ok((8 | 1) << 16));
        assert_eq!(b.read(CCR5, 4).map(|v| v & EN), Ok(0));
        assert_ne!(b.last_irq_lines & (1 << 15), 0);
        assert_eq!(b.spi2.next_event(), None, "nothing was sent");
    }

    #[test]
    fn dma1_needs_its_clock() {
        let mut b = Board::new(Flash::new(None).unwrap(), 0x2_0000..0x2_0000);
        assert!(b.read(CCR5, 4).is_err());
    }
}
