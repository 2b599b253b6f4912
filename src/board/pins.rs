//! GPIO ports: the register-level helpers the owners below use (one BSRR store per
//! write, IDR reads) and every pin's mode, written at boot from the pin table in
//! [`super`].

use stm32f1xx_hal::pac;

/// A GPIO port's register block (GPIOA, GPIOB and GPIOC share the layout).
pub(super) type GpioRegs = pac::gpioa::RegisterBlock;

/// One store to a GPIO port's bit set/reset register.
#[inline(always)]
pub(super) fn bsrr(port: *const GpioRegs, word: u32) {
    // SAFETY: BSRR is write-only and atomic per bit; callers only name pins that their
    // owner (a struct made by `init`) drives.
    unsafe {
        (*port).bsrr().write(|w| w.bits(word));
    }
}

/// The BSRR word that drives pin `n` high or low.
#[inline(always)]
pub(super) const fn pin_word(n: u32, high: bool) -> u32 {
    if high {
        1 << n
    } else {
        1 << (n + 16)
    }
}

/// A port's input data register.
#[inline(always)]
pub(super) fn idr(port: *const GpioRegs) -> u32 {
    // SAFETY: read-only access to an input register.
    unsafe { (*port).idr().read().bits() }
}

/// Pin configuration nibbles (RM0008 9.2: CNF[1:0] MODE[1:0]; outputs at 50 MHz, the
/// same values as the HAL's pin modes). A pull-up input also needs its ODR bit set.
const IN_FLOAT: u32 = 0x4;
const IN_PULL: u32 = 0x8;
const OUT_PP: u32 = 0x3;
const OUT_OD: u32 = 0x7;
const AF_PP: u32 = 0xB;

/// A configuration register from the nibbles of its eight pins (lowest pin first).
const fn cr(n: [u32; 8]) -> u32 {
    let mut v = 0;
    let mut i = 0;
    while i < 8 {
        v |= n[i] << (4 * i);
        i += 1;
    }
    v
}

/// GPIOA: PA0-PA7 motion outputs; PA8 servo (TIM1 CH1); PA9 driver enable, high =
/// disabled; PA10 buzzer; PA11/PA12 USB (PA12 first driven low, see `init`); PA13/14
/// SWD as reset; PA15 keypad column 3, released high.
const PA_CRH: [u32; 8] = [
    AF_PP, OUT_PP, OUT_PP, IN_FLOAT, OUT_PP, IN_FLOAT, IN_FLOAT, OUT_OD,
];
pub(super) const PA_CRH_USB: u32 = (cr(PA_CRH) & !(0xF << 16)) | (IN_FLOAT << 16);
/// (port, ODR, CRL, CRH) of GPIOA, GPIOB and GPIOC, the pin table at the top.
pub(super) const PORTS: [(*const GpioRegs, u32, u32, u32); 3] = [
    (
        pac::GPIOA::ptr(),
        (1 << 9) | (1 << 15),
        cr([OUT_PP; 8]),
        cr(PA_CRH),
    ),
    // PB0, PB1, PB3-PB5 switch inputs and PB6-PB9 keypad rows with pull-ups; PB2
    // (BOOT1) as reset; PB10/PB11 keypad columns released high; PB12 LCD CS low;
    // PB13/PB15 SPI2 SCK/MOSI; PB14 unused.
    (
        pac::GPIOB::ptr(),
        0x0FFB,
        cr([
            IN_PULL, IN_PULL, IN_FLOAT, IN_PULL, IN_PULL, IN_PULL, IN_PULL, IN_PULL,
        ]),
        cr([
            IN_PULL, IN_PULL, OUT_OD, OUT_OD, OUT_PP, AF_PP, IN_FLOAT, AF_PP,
        ]),
    ),
    // PC13 busy LED off (high), PC14 keypad column 4 released high, PC15 busy out low.
    (
        pac::GPIOC::ptr(),
        (1 << 13) | (1 << 14),
        cr([IN_FLOAT; 8]),
        cr([
            IN_FLOAT, IN_FLOAT, IN_FLOAT, IN_FLOAT, IN_FLOAT, OUT_PP, OUT_OD, OUT_PP,
        ]),
    ),
];
