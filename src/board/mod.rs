//! The Blue Pill board: the pin map, the clocks and [`init`], which sets every
//! peripheral up; each peripheral's owner lives in a module of its own (step port and
//! step timer, servo, keypad, inputs, indicators, watchdog, LCD, USB, flash).
//!
//! This is the only module that knows which pin does what. Everything it hands out is
//! a small owner of one job (step port, keypad matrix, LCD, USB, ...) whose methods are
//! plain register accesses; all decisions are taken in `inkstep-core`.
//!
//! | pin      | signal                          | notes                                          |
//! |----------|---------------------------------|------------------------------------------------|
//! | PA0      | X STEP  (4-phase: X coil A)     | TIM2 CH1-CH3 in step/dir mode: the timer draws |
//! | PA1      | Y STEP  (4-phase: X coil B)     | the pulses; GPIO in 4-phase mode. All motion   |
//! | PA2      | Z STEP  (4-phase: X coil C)     | outputs on GPIOA: one BSRR store sets the rest |
//! | PA3      | X DIR   (4-phase: X coil D)     |                                                |
//! | PA4      | Y DIR   (4-phase: Y coil A)     |                                                |
//! | PA5      | Z DIR   (4-phase: Y coil B)     |                                                |
//! | PA6      | (4-phase: Y coil C)             | unused in step/dir mode                        |
//! | PA7      | (4-phase: Y coil D)             | unused in step/dir mode                        |
//! | PA8      | pen servo PWM (TIM1 CH1, 50 Hz) | 5 V servo signal is fine from 3.3 V            |
//! | PA9      | stepper ENABLE                  | active low (A4988/DRV8825 /EN); `$4` inverts   |
//! | PA10     | buzzer                          | active high, through a transistor              |
//! | PA11/12  | USB D-/D+                       | CDC-ACM serial; PA12 pulled low at boot        |
//! | PA13/14  | SWDIO/SWCLK                     | probe-rs; JTAG is disabled, SWD stays          |
//! | PA15     | keypad column 3                 | open-drain, driven low to scan                 |
//! | PB0      | E-STOP input (EXTI0)            | pull-up; wire NC to GND, open = stop           |
//! | PB1      | X limit/home switch (EXTI1)     | pull-up; NC to GND, `$5` inverts               |
//! | PB3      | Y limit/home switch (EXTI3)     | pull-up; NC to GND                             |
//! | PB4      | feed hold / SYNC in (EXTI4)     | pull-up; low = pause (the seed's SYNC input)   |
//! | PB5      | cycle start (EXTI5)             | pull-up; falling edge = resume                 |
//! | PB6-PB9  | keypad rows 1-4                 | pull-up inputs, read together from GPIOB IDR   |
//! | PB10     | keypad column 1                 | open-drain                                     |
//! | PB11     | keypad column 2                 | open-drain                                     |
//! | PB12     | LCD CS (ST7920 RS)              | active high, held high (frames sync themselves)|
//! | PB13     | LCD SCK (ST7920 E)              | SPI2 mode 0, 281 kHz, fed by DMA1 channel 5    |
//! | PB15     | LCD MOSI (ST7920 R/W)           | ST7920 PSB tied low (serial mode)              |
//! | PC13     | busy LED (on board)             | active low                                     |
//! | PC14     | keypad column 4                 | open-drain (low-speed pin, fine for a keypad)  |
//! | PC15     | busy output                     | high while moving, for syncing controllers     |

mod flash;
mod indicators;
mod inputs;
mod keypad;
mod lcd;
mod servo;
mod step_port;
mod step_timer;
mod usb;
mod watchdog;

pub use flash::{
    flash_size_kb, settings_pages, FlashError, SettingsFlash, FLASH_PAGE_SIZE, FLASH_SIZE,
};
pub use indicators::{BusyOutputs, Indicators};
pub use inputs::{exti_take_pending, Inputs};
pub use keypad::KeypadMatrix;
pub use lcd::{lcd_init, LcdSpi, INIT_SEQUENCE, LCD_CHUNK, LCD_SPI_HZ, POWER_UP_MS};
pub use servo::PenServo;
pub use step_port::{
    bsrr_word, coils_off, drivers_enabled, emergency_outputs_off, set_enable_polarity,
    step_outputs, StepPins, StepPort, DIR_SHIFT, MOTION_PINS, STEP_MASK_X, STEP_MASK_Y,
    STEP_MASK_Z,
};
pub use step_timer::{
    count_late_step_arming, disarm_step_pulses, late_step_armings, stop_step_timer, StepTimer,
};
pub use usb::{Usb, UsbCells, UsbSerial, USB_PACKET};
pub use watchdog::{Watchdog, WATCHDOG_MS};

use stm32f1xx_hal::{
    afio,
    dma::DmaExt,
    flash::FlashExt,
    gpio::{self, Edge, ExtiPin, Input, PinState},
    pac,
    prelude::*,
    rcc,
    spi::{Mode, Phase, Polarity, Spi},
    timer::{Channel, Tim1NoRemap},
    usb::{Peripheral, UsbBus, UsbBusType},
};
use usb_device::{bus::UsbBusAllocator, prelude::*};

/// System clock: 72 MHz from the 8 MHz crystal (PLL x9), APB1 36 MHz, USB 48 MHz.
pub const SYSCLK_HZ: u32 = 72_000_000;
/// The step timer (TIM2) counts at the full timer clock (APB1 x2 = 72 MHz, prescaler 1):
/// waits are exact to 14 ns; longer waits than 16 bits are split by the core's executor.
/// The core's step timing (and the simulator's) is computed for this clock.
pub const STEP_TIMER_HZ: u32 = inkstep_core::stepper::TIMER_HZ;

/// Everything `init` hands to the RTIC app.
pub struct Board {
    pub step_port: StepPort,
    pub step_timer: StepTimer,
    pub servo: PenServo,
    pub keypad: KeypadMatrix,
    pub inputs: Inputs,
    pub indicators: Indicators,
    pub busy: BusyOutputs,
    pub lcd_spi: LcdSpi,
    pub usb: &'static mut Usb,
    pub serial: &'static mut UsbSerial,
    pub watchdog: Watchdog,
    pub flash: SettingsFlash,
    pub sysclk_hz: u32,
}

/// Bring up the clocks and every peripheral. Called once from `init` with interrupts off.
///
/// `usb` is the 'static home of the USB stack (an RTIC init local); each call needs
/// its own (init runs once).
///
/// `usb_priority` is the RTIC priority of the one task that uses the USB device and
/// serial port: stm32-usbd's sections mask only the interrupts at or below it (see
/// `vendor/stm32-usbd`), so the step timer, the tick and the e-stop above it are never
/// held back by a packet copy. A priority above every level (`u8::MAX`) keeps the
/// driver's upstream sections, which mask every interrupt.
pub fn init(dp: pac::Peripherals, usb: &'static mut UsbCells, usb_priority: u8) -> Board {
    align_exception_frames();
    let mut flash = dp.FLASH.constrain();
    let mut rcc = dp.RCC.freeze(
        rcc::Config::hse(8.MHz())
            .sysclk(SYSCLK_HZ.Hz())
            .hclk(SYSCLK_HZ.Hz())
            .pclk1(36.MHz())
            .pclk2(72.MHz()),
        &mut flash.acr,
    );
    let sysclk_hz = rcc.clocks.sysclk().raw();

    let mut afio = dp.AFIO.constrain(&mut rcc);
    let mut gpioa = dp.GPIOA.split(&mut rcc);
    let mut gpiob = dp.GPIOB.split(&mut rcc);
    let mut gpioc = dp.GPIOC.split(&mut rcc);
    let mut exti = dp.EXTI;

    // JTAG off, SWD on: frees PA15, PB3, PB4.
    let (pa15, pb3, pb4) = afio.mapr.disable_jtag(gpioa.pa15, gpiob.pb3, gpiob.pb4);

    // The motion outputs low, the drivers disabled (/EN high) until the settings say
    // how to enable them.
    let (crl, crh) = (&mut gpioa.crl, &mut gpioa.crh);
    let step_pins = StepPins {
        pins: [
            gpioa.pa0.into_push_pull_output(crl).erase(),
            gpioa.pa1.into_push_pull_output(crl).erase(),
            gpioa.pa2.into_push_pull_output(crl).erase(),
            gpioa.pa3.into_push_pull_output(crl).erase(),
            gpioa.pa4.into_push_pull_output(crl).erase(),
            gpioa.pa5.into_push_pull_output(crl).erase(),
            gpioa.pa6.into_push_pull_output(crl).erase(),
            gpioa.pa7.into_push_pull_output(crl).erase(),
        ],
        enable: gpioa
            .pa9
            .into_push_pull_output_with_state(crh, PinState::High),
    };
    let (step_port, step_timer) = step_outputs(step_pins, dp.TIM2, dp.TIM3);

    let servo_pin = gpioa.pa8.into_alternate_push_pull(&mut gpioa.crh);
    let mut pwm = dp
        .TIM1
        .pwm_hz::<Tim1NoRemap, _, _>(servo_pin, &mut afio.mapr, 50.Hz(), &mut rcc);
    pwm.enable(Channel::C1);
    let servo = PenServo { pwm: pwm.split() };

    // Columns released (high), rows pulled up: a pressed key pulls its row low while
    // its column is driven low.
    let keypad = KeypadMatrix {
        columns: (
            gpiob
                .pb10
                .into_open_drain_output_with_state(&mut gpiob.crh, PinState::High),
            gpiob
                .pb11
                .into_open_drain_output_with_state(&mut gpiob.crh, PinState::High),
            pa15.into_open_drain_output_with_state(&mut gpioa.crh, PinState::High),
            gpioc
                .pc14
                .into_open_drain_output_with_state(&mut gpioc.crh, PinState::High),
        ),
        rows: (
            gpiob.pb6.into_pull_up_input(&mut gpiob.crl),
            gpiob.pb7.into_pull_up_input(&mut gpiob.crl),
            gpiob.pb8.into_pull_up_input(&mut gpiob.crh),
            gpiob.pb9.into_pull_up_input(&mut gpiob.crh),
        ),
    };

    // The safety and control inputs on EXTI lines 0, 1, 3, 4, 5. E-stop and limits:
    // NC switches to GND, so opening (rising edge) is the event; both edges are taken
    // so that releasing is seen too, and feed hold likewise. Cycle start acts on
    // pressing (falling edge).
    let mut estop = gpiob.pb0.into_pull_up_input(&mut gpiob.crl);
    let mut limit_x = gpiob.pb1.into_pull_up_input(&mut gpiob.crl);
    let mut limit_y = pb3.into_pull_up_input(&mut gpiob.crl);
    let mut feed_hold = pb4.into_pull_up_input(&mut gpiob.crl);
    let mut cycle_start = gpiob.pb5.into_pull_up_input(&mut gpiob.crl);
    interrupt_on(&mut estop, Edge::RisingFalling, &mut afio, &mut exti);
    interrupt_on(&mut limit_x, Edge::RisingFalling, &mut afio, &mut exti);
    interrupt_on(&mut limit_y, Edge::RisingFalling, &mut afio, &mut exti);
    interrupt_on(&mut feed_hold, Edge::RisingFalling, &mut afio, &mut exti);
    interrupt_on(&mut cycle_start, Edge::Falling, &mut afio, &mut exti);
    let inputs = Inputs {
        _estop: estop,
        _limit_x: limit_x,
        _limit_y: limit_y,
        _feed_hold: feed_hold,
        _cycle_start: cycle_start,
    };

    // Not busy: the LED (active low) off, the busy output low, the buzzer quiet.
    let busy = BusyOutputs {
        led: gpioc
            .pc13
            .into_push_pull_output_with_state(&mut gpioc.crh, PinState::High),
        busy_out: gpioc.pc15.into_push_pull_output(&mut gpioc.crh),
    };
    let indicators = Indicators {
        buzzer: gpioa.pa10.into_push_pull_output(&mut gpioa.crh),
    };

    // LCD on SPI2. The ST7920 samples on the rising edge with the clock idle low.
    let sck = gpiob.pb13.into_alternate_push_pull(&mut gpiob.crh);
    let mosi = gpiob.pb15.into_alternate_push_pull(&mut gpiob.crh);
    let spi = Spi::new(
        dp.SPI2,
        (
            Some(sck),
            None::<gpio::PB14<Input<gpio::Floating>>>,
            Some(mosi),
        ),
        Mode {
            polarity: Polarity::IdleLow,
            phase: Phase::CaptureOnFirstTransition,
        },
        LCD_SPI_HZ.Hz(),
        &mut rcc,
    );
    // Its transmit DMA, DMA1 channel 5 (the only channel SPI2_TX has, RM0008 table
    // 78), reading a static buffer. Chip select high for good (see `lcd`).
    let dma1 = dp.DMA1.split(&mut rcc);
    let lcd_buf = cortex_m::singleton!(: [u8; LCD_CHUNK] = [0; LCD_CHUNK])
        // `init` runs once.
        .unwrap_or_else(|| defmt::panic!("lcd buffer"));
    let lcd_spi = LcdSpi::new(
        spi.with_tx_dma(dma1.5),
        gpiob
            .pb12
            .into_push_pull_output_with_state(&mut gpiob.crh, PinState::High),
        lcd_buf,
    );

    // USB: force a re-enumeration by pulling D+ low briefly (the Blue Pill has a fixed
    // pull-up on D+), then hand the pins to the USB peripheral.
    let mut usb_dp = gpioa.pa12.into_push_pull_output(&mut gpioa.crh);
    usb_dp.set_low();
    cortex_m::asm::delay(sysclk_hz / 100);
    let usb_periph = Peripheral {
        usb: dp.USB,
        pin_dm: gpioa.pa11,
        pin_dp: usb_dp.into_floating_input(&mut gpioa.crh),
    };
    let bus: &'static UsbBusAllocator<UsbBusType> = usb.bus.write(UsbBus::new(usb_periph));
    // RTIC's hardware value of that priority (a higher priority is a lower value).
    let bits = pac::NVIC_PRIO_BITS;
    let level = ((1u8 << bits) - usb_priority.min(1 << bits).max(1)) << (8 - bits);
    // SAFETY: the caller's task at `usb_priority` is the only user of the bus and its
    // endpoints after `init` (which runs with interrupts off).
    unsafe { stm32_usbd::mask::mask_at_or_below(level) };
    let serial = usb.serial.write(UsbSerial::new(bus));
    let usb = usb.dev.write(
        UsbDeviceBuilder::new(bus, UsbVidPid(0x16c0, 0x27dd))
            .device_class(usbd_serial::USB_CLASS_CDC)
            .strings(&[StringDescriptors::default()
                .manufacturer("inkstep")
                .product("inkstep pen plotter (Grbl 1.1)")
                .serial_number("INKSTEP")])
            // One language with three short strings cannot exceed the builder's limits.
            .unwrap_or_else(|_| defmt::panic!("usb strings"))
            .build(),
    );

    let watchdog = Watchdog::start(dp.IWDG);

    let flash = SettingsFlash::new(flash);

    Board {
        step_port,
        step_timer,
        servo,
        keypad,
        inputs,
        indicators,
        busy,
        lcd_spi,
        usb,
        serial,
        watchdog,
        flash,
        sysclk_hz,
    }
}

/// An input pin's EXTI line raises its interrupt on `edge`.
fn interrupt_on(pin: &mut impl ExtiPin, edge: Edge, afio: &mut afio::Parts, exti: &mut pac::EXTI) {
    pin.make_interrupt_source(afio);
    pin.trigger_on_edge(exti, edge);
    pin.enable_interrupt(exti);
}

/// SCB.CCR.STKALIGN (ARMv7-M B3.2.8): exception entry aligns the stack to 8 bytes.
const STKALIGN: u32 = 1 << 9;

/// Makes exception entry keep the stack 8-byte aligned. The compiler relies on that
/// alignment in every function, handlers included (it forms the address of a stack
/// slot with ORR where that equals ADD), but the STM32F103's Cortex-M3 r1p1 resets
/// with CCR.STKALIGN clear: an interrupt taken with SP at 4 mod 8 then ran its task on
/// a misaligned stack and read the wrong locals (the preparation task traced an arc
/// the wrong way round: emu/tests/stack.rs). Called first in [`init`], before any
/// interrupt is enabled.
fn align_exception_frames() {
    // SAFETY: a read-modify-write of the core's configuration register during init,
    // with interrupts masked; nothing else writes CCR.
    unsafe {
        let scb = &*cortex_m::peripheral::SCB::PTR;
        scb.ccr.modify(|r| r | STKALIGN);
    }
}
