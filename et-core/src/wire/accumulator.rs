//! Packets reassembled from a byte stream, with resynchronisation.

use serde::de::DeserializeOwned;

use super::{WireError, decode};

/// Reassembles packets from a byte stream, one byte at a time, with resynchronisation: a
/// packet that overflows the buffer or fails to decode is dropped and the reader carries on at
/// the next 0x00. `N` is the buffer size ([`PACKET_MAX`] on the host, [`COMMAND_PACKET_MAX`]
/// on the device).
#[derive(Debug)]
pub struct Accumulator<const N: usize> {
    buf: [u8; N],
    len: usize,
    overflowed: bool,
}

impl<const N: usize> Default for Accumulator<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Accumulator<N> {
    /// An empty accumulator.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            len: 0,
            overflowed: false,
        }
    }

    /// Takes one byte; at a delimiter that ends a non-empty packet, decodes it.
    ///
    /// Returns `None` while a packet is in progress (or between two adjacent delimiters),
    /// `Some(Ok(message))` for a good packet, `Some(Err(e))` for a dropped one.
    pub fn feed<T: DeserializeOwned>(&mut self, byte: u8) -> Option<Result<T, WireError>> {
        if byte != 0 {
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => self.overflowed = true,
            }
            return None;
        }
        let (len, overflowed) = (self.len, self.overflowed);
        self.len = 0;
        self.overflowed = false;
        if overflowed {
            return Some(Err(WireError::Overflow));
        }
        if len == 0 {
            return None;
        }
        Some(
            self.buf
                .get_mut(..len)
                .map_or(Err(WireError::Overflow), decode),
        )
    }

    /// Takes `bytes` (any part of a stream) and calls `each` with every packet they end, in
    /// order: the same as [`Accumulator::feed`] byte by byte, but copying the bytes between
    /// delimiters as blocks.
    pub fn feed_slice<T: DeserializeOwned>(
        &mut self,
        mut bytes: &[u8],
        mut each: impl FnMut(Result<T, WireError>),
    ) {
        while !bytes.is_empty() {
            let (part, rest) = match bytes.iter().position(|&b| b == 0) {
                Some(i) => (bytes.get(..i).unwrap_or_default(), bytes.get(i..)),
                None => (bytes, None),
            };
            match self.buf.get_mut(self.len..self.len + part.len()) {
                Some(slot) if !self.overflowed => {
                    slot.copy_from_slice(part);
                    self.len += part.len();
                }
                _ => self.overflowed = true,
            }
            let Some(rest) = rest else { return };
            // The delimiter: through the byte-wise path, which decodes and resets.
            if let Some(result) = self.feed(0) {
                each(result);
            }
            bytes = rest.get(1..).unwrap_or_default();
        }
    }

    /// Bytes of the packet in progress.
    #[must_use]
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Drops the packet in progress (e.g. after a reconnect).
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflowed = false;
    }
}
