#![no_std]
#![no_main]
use defmt_rtt as _;

#[no_mangle]
pub static mut BENCH_RESULT: [u32; 4] = [0; 4];

#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_tick(x: u32) -> u32 {
    let mut a = x;
    for i in 0..(x % 5) {
        a = a.wrapping_mul(3).wrapping_add(i);
    }
    a
}

#[cortex_m_rt::entry]
fn main() -> ! {
    let mut s = 0;
    for i in 0..10 {
        s += bench_tick(core::hint::black_box(i));
    }
    unsafe { BENCH_RESULT[0] = s };
    loop {
        cortex_m::asm::bkpt();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        cortex_m::asm::bkpt();
    }
}
