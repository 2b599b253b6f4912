//! What to send to the ST7920 for the dirty parts of a [`FrameBuffer`], and what it
//! costs: the serial byte encoding, dirty spans in GDRAM order, and the timing budget.
//!
//! ST7920 facts used (Sitronix ST7920 datasheet V4.0, serial interface and instruction
//! tables; the st7920 0.4 crate encodes the same way):
//! - Serial mode: every 8-bit instruction or data byte is one 24-bit frame: a start
//!   byte `0xF8 | RS << 1` (0xF8 command, 0xFA data), then the high nibble `D7..D4 0000`,
//!   then the low nibble `D3..D0 0000`. So 3 SPI bytes per display byte.
//! - The controller has no input buffer: the MPU must wait each instruction's execution
//!   time, 72 us for "write data to RAM" and for address settings (at f_OSC 540 kHz),
//!   before the next frame.
//! - Graphics RAM (extended instruction set) is 32 rows of 256 pixels: GDRAM row r holds
//!   screen row r in words 0..7 and screen row r + 32 in words 8..15. An address is two
//!   commands, `0x80 | r` (vertical) then `0x80 | word` (horizontal); each word is 2 data
//!   bytes and the address auto-increments across the whole 16-word GDRAM row.
//!
//! Chosen SPI clock: 72 MHz / 256 = 281.25 kHz (SPI1 on APB2, or SPI2 at 36 MHz / 128).
//! One 24-bit frame then takes 85.3 us >= 72 us, so the SPI itself paces the writes:
//! the firmware sends the spans by DMA ([`encode_chunk`] packs them a buffer at a
//! time) without CPU-timed gaps, from the lowest-priority task, and never touches the
//! step timer. Worst case (every pixel changed): 32 spans of
//! (2 address commands + 32 data bytes) = 1088 frames = 3264 SPI bytes = 92.8 ms, so a
//! full refresh still fits a 10 Hz frame (100 ms). Typical drawing-screen updates are a
//! small fraction of that (see the tests and the README).
//!
//! Why not the st7920 crate (0.4): it owns the SPI, the chip select and a reset pin
//! through embedded-hal, keeps its own 1 KB buffer and sends it whole on `flush`
//! (92.8 ms at this clock). Here the core's [`FrameBuffer`] tracks which words changed
//! and this module encodes only those spans into plain bytes, so the partial update
//! is tested on the host (the tests below, the snapshot tests) and the board only
//! moves bytes. Its start-up sequence is the crate's (`board::lcd_init`).

use super::framebuffer::{FrameBuffer, HEIGHT, ROW_WORDS};

/// SPI clock of the LCD link.
pub const SPI_HZ: u32 = 281_250;
/// SPI bytes per display byte (start byte + two nibble bytes).
pub const BYTES_PER_WRITE: usize = 3;
/// GDRAM rows (each covers two screen rows).
pub const GDRAM_ROWS: usize = HEIGHT / 2;
/// Words per GDRAM row.
pub const GDRAM_WORDS: usize = 2 * ROW_WORDS;
/// The largest encoded span: address (2 commands) + 16 words of 2 bytes.
pub const MAX_SPAN_BYTES: usize = (2 + 2 * GDRAM_WORDS) * BYTES_PER_WRITE;
/// Worst-case bytes of one refresh (every word dirty).
pub const FULL_FRAME_BYTES: usize = GDRAM_ROWS * MAX_SPAN_BYTES;

/// A run of GDRAM words `first..=last` in GDRAM row `row`, sent after one address.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    pub row: u8,
    pub first: u8,
    pub last: u8,
}

impl Span {
    pub fn words(&self) -> usize {
        (self.last as usize + 1).saturating_sub(self.first as usize)
    }

    /// SPI bytes to send this span.
    pub fn bytes(&self) -> usize {
        (2 + 2 * self.words()) * BYTES_PER_WRITE
    }
}

/// Dirty mask of GDRAM row `r`: bits 0..7 from screen row r, 8..15 from row r + 32.
fn gdram_mask(fb: &FrameBuffer, r: usize) -> u16 {
    fb.dirty_words(r) as u16 | (fb.dirty_words(r + GDRAM_ROWS) as u16) << 8
}

/// The dirty spans of `fb`, in GDRAM order. A single clean word between two dirty ones
/// is sent rather than skipped: resending it (2 writes) costs the same as a new address
/// (2 commands), and makes fewer transfers.
pub fn spans(fb: &FrameBuffer) -> impl Iterator<Item = Span> + '_ {
    (0..GDRAM_ROWS).flat_map(move |r| {
        let mask = gdram_mask(fb, r);
        let mut w = 0usize;
        core::iter::from_fn(move || next_span(mask, r, &mut w))
    })
}

/// The next span of GDRAM row `r` (dirty mask `mask`) from word `*w` on.
fn next_span(mask: u16, r: usize, w: &mut usize) -> Option<Span> {
    while *w < GDRAM_WORDS && mask & (1 << *w) == 0 {
        *w += 1;
    }
    if *w >= GDRAM_WORDS {
        return None;
    }
    let first = *w;
    let mut last = *w;
    *w += 1;
    while *w < GDRAM_WORDS {
        if mask & (1 << *w) != 0 {
            last = *w;
            *w += 1;
        } else if *w + 1 < GDRAM_WORDS && mask & (1 << (*w + 1)) != 0 {
            last = *w + 1;
            *w += 2;
        } else {
            break;
        }
    }
    Some(Span {
        row: r as u8,
        first: first as u8,
        last: last as u8,
    })
}

fn frame(out: &mut [u8], at: &mut usize, start: u8, byte: u8) {
    for &b in [start, byte & 0xF0, byte << 4].iter() {
        if let Some(slot) = out.get_mut(*at) {
            *slot = b;
            *at += 1;
        }
    }
}

/// Encode `span` as the SPI bytes to send (address, then data). Returns the length;
/// `out` of [`MAX_SPAN_BYTES`] always suffices.
pub fn encode(fb: &FrameBuffer, span: Span, out: &mut [u8]) -> usize {
    let mut n = 0;
    frame(out, &mut n, 0xF8, 0x80 | (span.row & 0x1F));
    frame(out, &mut n, 0xF8, 0x80 | (span.first & 0x0F));
    for w in span.first as usize..span.last as usize + 1 {
        let (y, word) = if w < ROW_WORDS {
            (span.row as usize, w)
        } else {
            (span.row as usize + GDRAM_ROWS, w - ROW_WORDS)
        };
        let row = fb.row(y);
        for i in 0..2 {
            let byte = row.get(word * 2 + i).copied().unwrap_or(0);
            frame(out, &mut n, 0xFA, byte);
        }
    }
    n
}

/// SPI bytes needed to bring the LCD up to date with `fb`.
pub fn pending_bytes(fb: &FrameBuffer) -> usize {
    spans(fb).map(|s| s.bytes()).sum()
}

/// Send every dirty span through `send` (one call per span, at most
/// [`MAX_SPAN_BYTES`] bytes each, e.g. a blocking SPI write or a DMA transfer awaited by
/// the caller), then mark the buffer clean. On an error the buffer stays dirty, so the
/// next flush resends everything not confirmed. Returns the bytes sent.
pub fn flush<E>(
    fb: &mut FrameBuffer,
    mut send: impl FnMut(&[u8]) -> Result<(), E>,
) -> Result<usize, E> {
    let mut buf = [0u8; MAX_SPAN_BYTES];
    let mut total = 0;
    // The same spans as [`spans`], walked with plain loops (no iterator adapters).
    for r in 0..GDRAM_ROWS {
        let mask = gdram_mask(fb, r);
        let mut w = 0;
        while let Some(span) = next_span(mask, r, &mut w) {
            let n = encode(fb, span, &mut buf);
            send(buf.get(..n).unwrap_or(&[]))?;
            total += n;
        }
    }
    fb.mark_clean();
    Ok(total)
}

/// Where the next chunk of a refresh starts: a GDRAM row and word (see
/// [`encode_chunk`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cursor {
    row: u8,
    word: u8,
}

impl Cursor {
    /// The top of the screen: a refresh starts here.
    pub const START: Cursor = Cursor { row: 0, word: 0 };
}

/// The bytes of a refresh, a buffer at a time, for a transfer that sends each buffer
/// whole (DMA): encode the dirty spans of `fb` from `at` on into `out`, as many whole
/// spans as fit, in the order [`flush`] sends them. Returns the bytes written and where
/// the next chunk starts (None: the last span is in, the caller marks `fb` clean once
/// it is sent). An `out` of [`MAX_SPAN_BYTES`] holds at least one span, so every
/// chunk makes progress; a smaller one that cannot hold the next span gets 0 bytes
/// and the same cursor back.
pub fn encode_chunk(fb: &FrameBuffer, at: Cursor, out: &mut [u8]) -> (usize, Option<Cursor>) {
    let mut n = 0;
    let mut r = at.row as usize;
    let mut w = at.word as usize;
    while r < GDRAM_ROWS {
        let mask = gdram_mask(fb, r);
        let mut next = w;
        while let Some(span) = next_span(mask, r, &mut next) {
            let room = out.len() - n;
            if span.bytes() > room {
                let cursor = Cursor {
                    row: r as u8,
                    word: span.first,
                };
                return (n, Some(cursor));
            }
            n += encode(fb, span, out.get_mut(n..).unwrap_or(&mut []));
        }
        r += 1;
        w = 0;
    }
    (n, None)
}

/// Time to clock `bytes` out at [`SPI_HZ`], in microseconds.
pub fn transfer_us(bytes: usize) -> u32 {
    ((bytes as u64 * 8 * 1_000_000).div_ceil(SPI_HZ as u64)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worst_case_refresh_fits_ten_hertz() {
        let fb = FrameBuffer::new(); // all dirty
        assert_eq!(spans(&fb).count(), 32);
        assert_eq!(pending_bytes(&fb), FULL_FRAME_BYTES);
        assert_eq!(FULL_FRAME_BYTES, 3264);
        let us = transfer_us(FULL_FRAME_BYTES);
        assert_eq!(us, 92_843);
        assert!(us < 100_000);
        // Each 24-bit frame outlasts the controller's 72 us execution time.
        assert!(transfer_us(BYTES_PER_WRITE) >= 72);
    }

    #[test]
    fn spans_merge_single_gaps_and_join_the_two_screen_halves() {
        let mut fb = FrameBuffer::new();
        fb.mark_clean();
        fb.set(0, 5, true); // word 0
        fb.set(32, 5, true); // word 2 (gap of one: merged)
        fb.set(112, 5, true); // word 7
        fb.set(0, 37, true); // row 37 = GDRAM row 5, word 8: joins word 7
        fb.set(80, 37, true); // word 13 (gap of four: new span)
        let s: std::vec::Vec<Span> = spans(&fb).collect();
        assert_eq!(
            s,
            [
                Span {
                    row: 5,
                    first: 0,
                    last: 2
                },
                Span {
                    row: 5,
                    first: 7,
                    last: 8
                },
                Span {
                    row: 5,
                    first: 13,
                    last: 13
                },
            ]
        );
    }

    #[test]
    fn encoding_is_address_then_nibble_split_data() {
        let mut fb = FrameBuffer::new();
        fb.mark_clean();
        for x in 0..4 {
            fb.set(16 + x, 33, true); // GDRAM row 1, word 9: bytes 0xF0, 0x00
        }
        let span = spans(&fb).next().unwrap();
        assert_eq!(
            span,
            Span {
                row: 1,
                first: 9,
                last: 9
            }
        );
        let mut out = [0u8; MAX_SPAN_BYTES];
        let n = encode(&fb, span, &mut out);
        assert_eq!(n, span.bytes());
        assert_eq!(
            &out[..n],
            [0xF8, 0x80, 0x10, 0xF8, 0x80, 0x90, 0xFA, 0xF0, 0x00, 0xFA, 0x00, 0x00]
        );
    }

    /// Chunks of any size from one span up carry exactly the bytes that `flush`
    /// sends, in its order, each chunk whole spans only.
    #[test]
    fn chunks_carry_the_flush_bytes_in_order() {
        let mut seed = 0x2468_ace1u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            seed >> 8
        };
        for case in 0..40 {
            let mut fb = FrameBuffer::new();
            if case > 0 {
                fb.mark_clean();
                for _ in 0..(next() % 300) {
                    fb.set((next() % 128) as i32, (next() % 64) as i32, true);
                }
            }
            let mut spans_sent = std::vec::Vec::new();
            let mut reference = fb.clone();
            flush(&mut reference, |b: &[u8]| {
                spans_sent.push(b.to_vec());
                Ok::<(), ()>(())
            })
            .unwrap();
            let expected: std::vec::Vec<u8> = spans_sent.concat();
            for size in [
                MAX_SPAN_BYTES,
                MAX_SPAN_BYTES + 7,
                3 * MAX_SPAN_BYTES,
                FULL_FRAME_BYTES,
            ] {
                let mut out = std::vec![0u8; size];
                let mut got = std::vec::Vec::new();
                let mut at = Some(Cursor::START);
                let mut chunks = 0;
                while let Some(c) = at {
                    let (n, rest) = encode_chunk(&fb, c, &mut out);
                    assert!(n > 0 || expected.is_empty());
                    got.extend_from_slice(&out[..n]);
                    at = rest;
                    chunks += 1;
                    assert!(chunks <= spans_sent.len().max(1));
                }
                assert_eq!(got, expected, "case {case}, chunk of {size}");
            }
        }
        // Too small for the next span: nothing, and the same place again.
        let fb = FrameBuffer::new();
        let mut tiny = [0u8; 5];
        assert_eq!(
            encode_chunk(&fb, Cursor::START, &mut tiny),
            (0, Some(Cursor::START))
        );
    }

    #[test]
    fn flush_sends_each_span_once_and_cleans_only_on_success() {
        let mut fb = FrameBuffer::new();
        fb.mark_clean();
        fb.set(0, 0, true);
        fb.set(127, 63, true);
        let failed: Result<usize, ()> = flush(&mut fb, |_| Err(()));
        assert!(failed.is_err() && fb.is_dirty());
        let mut sent = std::vec::Vec::new();
        let n = flush(&mut fb, |b: &[u8]| {
            sent.push(b.to_vec());
            Ok::<(), ()>(())
        })
        .unwrap();
        assert_eq!(sent.len(), 2);
        assert_eq!(n, sent.iter().map(|b| b.len()).sum::<usize>());
        assert!(!fb.is_dirty());
        assert_eq!(flush(&mut fb, |_| Err(())), Ok::<usize, ()>(0));
    }
}
