//! Talking to the board from the command line: the `send` and `ports` commands
//! around inkstep-serial's stream and port.

pub mod send;
