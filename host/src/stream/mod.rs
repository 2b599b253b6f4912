//! Talking to the board: Grbl replies (grbl), character-counting streaming
//! over any transport (streamer), and the `send`/`ports` commands around a
//! serial port (send).

pub mod grbl;
pub mod send;
pub mod streamer;
