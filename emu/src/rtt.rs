//! The defmt log over RTT, read the way a debug probe reads it: the `_SEGGER_RTT`
//! control block in RAM, up channel 0's ring buffer (the target advances its write
//! offset, the host its read offset), and the bytes decoded with the defmt-decoder
//! crate from the table in the ELF's `.defmt` section.

use defmt_decoder::{DecodeError, StreamDecoder, Table};

/// Offsets in the control block (SEGGER RTT: 16-byte id, two counts, then the up
/// channel descriptors of 24 bytes: name, buffer, size, write, read, flags).
pub const UP0: u32 = 16 + 8;
pub const UP_WRITE: u32 = 12;
pub const UP_READ: u32 = 16;

pub struct Log {
    decoder: Box<dyn StreamDecoder + Send + Sync>,
    /// Decoded lines so far.
    pub lines: Vec<String>,
    /// Echo each line to stderr as it is decoded.
    pub echo: bool,
}

impl Log {
    pub fn new(elf: &[u8]) -> Result<Log, String> {
        let table = Table::parse(elf)
            .map_err(|e| format!("defmt table: {e}"))?
            .ok_or("the ELF has no .defmt section")?;
        // The decoder borrows its table for the whole run.
        let table: &'static Table = Box::leak(Box::new(table));
        Ok(Log {
            decoder: table.new_stream_decoder(),
            lines: Vec::new(),
            echo: false,
        })
    }

    /// Bytes read from the up channel, at virtual time `t_us`.
    pub fn received(&mut self, bytes: &[u8], t_us: f64) {
        self.decoder.received(bytes);
        loop {
            match self.decoder.decode() {
                Ok(frame) => {
                    let level = frame
                        .level()
                        .map(|l| l.as_str().to_uppercase())
                        .unwrap_or_else(|| "PRINT".into());
                    let line = format!(
                        "{:>12.3} ms {level:<5} {}",
                        t_us / 1000.0,
                        frame.display_message()
                    );
                    if self.echo {
                        eprintln!("{line}");
                    }
                    self.lines.push(line);
                }
                Err(DecodeError::UnexpectedEof) => break,
                Err(DecodeError::Malformed) => {
                    self.lines.push("(malformed defmt frame)".into());
                    break;
                }
            }
        }
    }
}
