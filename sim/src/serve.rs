//! `cargo sim serve`: the virtual board behind a pseudo-terminal, so that any Grbl
//! sender can connect to it like to the board's USB serial port.
//!
//! Owns the real-time pacing only: virtual time follows the wall clock (times `speed`),
//! and bytes cross between the pty and the board's USB entry points the moment they
//! arrive: with nothing to simulate the loop sleeps on the pty, and while it simulates
//! it comes back to the pty every [`IO_EVERY`] of real time, however far virtual time
//! has to go (at high speeds, or when the host falls behind, one long catch-up would
//! hold every `?` until it ended). The pty is the shared one of inkstep-serial; clients
//! opening and closing it are logged and are the board's port open/close (USB CDC's
//! DTR on the board): opening it brings the welcome line.

use crate::board::{Board, TICK_HZ};
use inkstep_core::settings::Settings;
use inkstep_serial::pty::{ClientEvent, Pty};
use std::path::Path;
use std::time::{Duration, Instant};

/// Longest stretch of real time spent simulating before the pty is served again.
pub const IO_EVERY: Duration = Duration::from_micros(200);
/// Virtual time simulated between two looks at the clock: one millisecond.
const SLICE: u64 = TICK_HZ / 1000;

/// Runs until `stop` returns true (for the command line: on Ctrl-C, SIGTERM or SIGHUP).
pub fn serve(
    link: Option<&Path>,
    speed: f64,
    mut stop: impl FnMut() -> bool,
) -> Result<(), String> {
    let mut pty = Pty::open().map_err(|e| format!("opening a pseudo-terminal: {e}"))?;
    if let Some(l) = link {
        pty.link_at(l)
            .map_err(|e| format!("{}: {e}", l.display()))?;
    }
    match link {
        Some(l) => println!(
            "inkstep simulator on {} (linked at {})",
            pty.path().display(),
            l.display()
        ),
        None => println!("inkstep simulator on {}", pty.path().display()),
    }
    use std::io::Write;
    let _ = std::io::stdout().flush();
    let mut board = Board::new(Settings::default());
    // Where the pty cannot tell, the port counts as open all along.
    if pty.notices_clients() {
        board.set_port_open(false);
    }
    let start = Instant::now();
    let mut inbox: Vec<u8> = Vec::new();
    let mut buf = [0u8; 1024];
    while !stop() {
        let n = pty.read_available(&mut buf).map_err(|e| e.to_string())?;
        inbox.extend_from_slice(&buf[..n]);
        if !inbox.is_empty() {
            let used = board.usb_write(&inbox);
            inbox.drain(..used);
        }
        let out = board.usb_read();
        if !out.is_empty() {
            pty.send(&out).map_err(|e| e.to_string())?;
        }
        pty.flush_pending().map_err(|e| e.to_string())?;
        for e in pty.client_events().map_err(|e| e.to_string())? {
            match e {
                ClientEvent::Opened => println!("a client opened the port"),
                ClientEvent::Closed => println!("a client closed the port"),
            }
            let _ = std::io::stdout().flush();
            board.set_port_open(pty.clients() > 0);
        }
        let target = (start.elapsed().as_secs_f64() * speed * TICK_HZ as f64) as u64;
        if target > board.now() {
            let began = Instant::now();
            while board.now() < target && began.elapsed() < IO_EVERY {
                board.run_until(target.min(board.now() + SLICE), &mut |_| {});
            }
        } else {
            // Caught up: sleep until bytes arrive or the next virtual millisecond.
            let next_ms = Duration::from_secs_f64(1e-3 / speed).min(Duration::from_millis(1));
            pty.wait_readable(next_ms).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}
