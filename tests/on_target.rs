#![no_std]
#![no_main]
use defmt_rtt as _;
use panic_probe as _;
use stm32f1xx_hal as _;

#[defmt_test::tests]
mod tests {
    #[test]
    fn placeholder() {
        defmt::assert!(true);
    }
}
