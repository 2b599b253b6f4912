#![no_std]
#![no_main]
use defmt_rtt as _;
use panic_probe as _;
use stm32f1xx_hal as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    defmt::info!("inkstep");
    loop {
        cortex_m::asm::wfi();
    }
}
