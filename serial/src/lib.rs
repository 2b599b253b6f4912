//! inkstep-serial: the serial side of inkstep, one of each for every program that
//! talks Grbl over a port.
//!
//! - [`pty`]: the pseudo-terminal that stands in for the board's USB serial port
//!   (the server side of `cargo sim serve` and `cargo emu serve`);
//! - [`port`]: the client side, a serial port (board or pty) as a byte pipe;
//! - [`grbl`]: what the controller says back, parsed, and what its numbers mean;
//! - [`sender`]: the one Grbl sender (send-response or character counting, answers
//!   matched to their lines), without I/O so that virtual time can drive it too;
//! - [`stream`]: a whole program streamed in wall-clock time with hello, status
//!   polls and clean handling of errors, alarms, stops and disconnects.

pub mod grbl;
pub mod port;
pub mod pty;
pub mod sender;
pub mod stream;
