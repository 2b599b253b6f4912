use inkstep_emu::clock::T_PER_MS;
use inkstep_emu::elf::Image;
use inkstep_emu::machine::Machine;
use inkstep_emu::periph::flash::Flash;

fn main() {
    let path = std::env::args().nth(1).unwrap_or("target/thumbv7m-none-eabi/release/inkstep".into());
    let image = Image::read(std::path::Path::new(&path)).unwrap();
    for (a, d) in &image.segments { println!("seg 0x{a:x} {}", d.len()); }
    println!("settings {:?}", image.symbol("_settings_start"));
    let mut m = Machine::new(&image, Flash::new(None).unwrap()).unwrap();
    m.state_mut().echo_log = true;
    println!("pc 0x{:x} sp 0x{:x}", m.uc.reg_read(unicorn_engine::RegisterARM::PC).unwrap(), m.uc.reg_read(unicorn_engine::RegisterARM::SP).unwrap());
    let mut n = 0u32; m.uc.add_block_hook(1, 0, move |uc, a, sz| { n += 1; if uc.get_data().instructions > 9600 { println!("blk 0x{a:x} {sz}"); } }).unwrap();
    let stop = m.run_until(300 * T_PER_MS);
    println!("usb configured {} at {:?} product {:?} rx {:?}", m.state().board.host.configured, m.state().board.host.configured_at.map(|t| t/144), m.state().board.host.product, String::from_utf8_lossy(&m.state().board.host.rx));
    println!("stop: {stop:?} at {} us, instructions {}", m.now() / 144, m.state().instructions);
}
