//! RCC, the reset and clock control (RM0008 section 7.3): oscillators, the PLL, the bus
//! prescalers and the peripheral clock enables and resets. Oscillators report ready
//! at once when switched on (their start-up times are not modelled). The clock tree
//! the firmware selects sets the CPU clock of the cycle model and the peripherals'
//! clocks.

use super::{unknown, Access};

pub struct Rcc {
    pub cr: u32,
    pub cfgr: u32,
    cir: u32,
    pub apb2rstr: u32,
    pub apb1rstr: u32,
    pub ahbenr: u32,
    pub apb2enr: u32,
    pub apb1enr: u32,
    bdcr: u32,
    /// CSR: reset flags (PINRSTF/PORRSTF at power-up, IWDGRSTF, SFTRSTF).
    pub csr: u32,
}

pub const HSI_HZ: u32 = 8_000_000;
/// The Blue Pill's crystal.
pub const HSE_HZ: u32 = 8_000_000;

impl Rcc {
    pub fn new() -> Rcc {
        Rcc {
            cr: 0x0000_0083,
            cfgr: 0,
            cir: 0,
            apb2rstr: 0,
            apb1rstr: 0,
            ahbenr: 0x14,
            apb2enr: 0,
            apb1enr: 0,
            bdcr: 0,
            // Power-on and pin reset.
            csr: 0x0C00_0000,
        }
    }

    /// After a system reset other than power-on: the reset flags in CSR survive.
    pub fn reset_keep_flags(&mut self, flag: u32) {
        let csr = self.csr;
        *self = Rcc::new();
        self.csr = (csr & 0xFE00_0000) | flag;
    }

    fn pll_hz(&self) -> u32 {
        let mul = ((self.cfgr >> 18) & 0xF) + 2;
        let mul = mul.min(16);
        let input = if self.cfgr & (1 << 16) != 0 {
            if self.cfgr & (1 << 17) != 0 {
                HSE_HZ / 2
            } else {
                HSE_HZ
            }
        } else {
            HSI_HZ / 2
        };
        input * mul
    }

    pub fn sysclk_hz(&self) -> u32 {
        match (self.cfgr >> 2) & 3 {
            1 => HSE_HZ,
            2 => self.pll_hz(),
            _ => HSI_HZ,
        }
    }

    pub fn hclk_hz(&self) -> u32 {
        let hpre = (self.cfgr >> 4) & 0xF;
        let div = if hpre < 8 { 1 } else { 2 << (hpre - 8) };
        // HPRE 0b1100.. skips /32 (RM0008 7.3.2).
        let div = if hpre >= 12 { div * 2 } else { div };
        self.sysclk_hz() / div
    }

    fn apb_div(ppre: u32) -> u32 {
        if ppre < 4 {
            1
        } else {
            2 << (ppre - 4)
        }
    }

    pub fn pclk1_hz(&self) -> u32 {
        self.hclk_hz() / Self::apb_div((self.cfgr >> 8) & 7)
    }

    pub fn pclk2_hz(&self) -> u32 {
        self.hclk_hz() / Self::apb_div((self.cfgr >> 11) & 7)
    }

    /// The timers' clock on APB1 (TIM2..4): x2 when APB1 is divided (RM0008 7.2).
    pub fn tim_apb1_hz(&self) -> u32 {
        let div = Self::apb_div((self.cfgr >> 8) & 7);
        self.pclk1_hz() * if div > 1 { 2 } else { 1 }
    }

    pub fn tim_apb2_hz(&self) -> u32 {
        let div = Self::apb_div((self.cfgr >> 11) & 7);
        self.pclk2_hz() * if div > 1 { 2 } else { 1 }
    }

    /// The USB clock: PLL / 1.5 (USBPRE = 0) or PLL (USBPRE = 1); must be 48 MHz.
    pub fn usb_hz(&self) -> u32 {
        if self.cfgr & (1 << 22) != 0 {
            self.pll_hz()
        } else {
            self.pll_hz() * 2 / 3
        }
    }

    pub fn read(&self, off: u32) -> Access<u32> {
        Ok(match off {
            0x00 => self.cr,
            0x04 => self.cfgr,
            0x08 => self.cir,
            0x0C => self.apb2rstr,
            0x10 => self.apb1rstr,
            0x14 => self.ahbenr,
            0x18 => self.apb2enr,
            0x1C => self.apb1enr,
            0x20 => self.bdcr,
            0x24 => self.csr,
            _ => return Err(unknown("RCC", off)),
        })
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access<()> {
        match off {
            0x00 => {
                // Writable: HSION 0, HSITRIM 7:3, HSEON 16, HSEBYP 18, CSSON 19, PLLON 24.
                let w = v & 0x010D_00F9;
                let mut cr = (self.cr & !0x010D_00F9) | w;
                // Ready flags follow their enables (start-up not modelled).
                let follow = |cr: &mut u32, on: u32, rdy: u32| {
                    if *cr & on != 0 {
                        *cr |= rdy;
                    } else {
                        *cr &= !rdy;
                    }
                };
                follow(&mut cr, 1 << 0, 1 << 1);
                follow(&mut cr, 1 << 16, 1 << 17);
                follow(&mut cr, 1 << 24, 1 << 25);
                self.cr = cr;
            }
            0x04 => {
                // SWS (3:2) follows SW (1:0) at once.
                let sw = v & 3;
                self.cfgr = (v & !0xC & 0x077F_FFF3) | (sw << 2);
            }
            0x08 => {
                // The ready flags are never raised here (oscillators are ready at
                // once, without interrupts); the enables are kept, the clear bits
                // are write-only.
                self.cir = v & 0x1F00;
            }
            0x0C => self.apb2rstr = v,
            0x10 => self.apb1rstr = v,
            0x14 => self.ahbenr = v & 0x557,
            0x18 => self.apb2enr = v,
            0x1C => self.apb1enr = v,
            0x20 => self.bdcr = v,
            0x24 => {
                // RMVF clears the reset flags; LSION/LSIRDY follow.
                let mut csr = (self.csr & 0xFC00_0000) | (v & 1);
                if v & (1 << 24) != 0 {
                    csr &= 0x00FF_FFFF;
                }
                if csr & 1 != 0 {
                    csr |= 2;
                }
                self.csr = csr;
            }
            _ => return Err(unknown("RCC", off)),
        }
        Ok(())
    }
}

impl Default for Rcc {
    fn default() -> Self {
        Self::new()
    }
}
