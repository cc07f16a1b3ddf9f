//! Model storage on the board: two slots in the upper half of the flash (docs/design.md: uploads go
//! to the slot that is not active, so a failed upload never destroys the working model).
//!
//! | slot | sectors | address | size |
//! | --- | --- | --- | --- |
//! | 0 | 6, 7, 8 | 0x0804_0000 | 384 KiB |
//! | 1 | 9, 10, 11 | 0x080A_0000 | 384 KiB |
//!
//! `memory.x` gives the program the first 256 KiB only, so code never lands in a slot. Erasing
//! a 128 KiB sector takes 1 to 2 s and stalls the CPU (it runs from the same flash): the host
//! waits for the acknowledgement of `ModelBegin` before it sends the first chunk.

use et_core::device::ModelStore;
use stm32f4xx_hal::flash::{Error, FlashExt as _};
use stm32f4xx_hal::pac::FLASH;

/// Bytes per slot (`et_core::board::SLOT_BYTES`: a model of up to `MODEL_SLOT_BYTES`, as the
/// host sizes models, and the record of its commit at the slot's end).
pub use et_core::board::SLOT_BYTES;
/// Offset of slot 0 from the start of flash.
const SLOT0: usize = 0x4_0000;
/// First sector of each slot.
const FIRST_SECTOR: [u8; 2] = [6, 9];

/// The two flash slots.
pub struct FlashStore {
    flash: FLASH,
}

impl FlashStore {
    /// Takes the flash controller.
    pub fn new(flash: FLASH) -> Self {
        Self { flash }
    }

    fn base(slot: usize) -> usize {
        SLOT0 + slot.min(1) * SLOT_BYTES
    }
}

impl ModelStore for FlashStore {
    type Error = Error;

    fn capacity(&self) -> usize {
        SLOT_BYTES
    }

    fn erase(&mut self, slot: usize) -> Result<(), Error> {
        let first = FIRST_SECTOR[slot.min(1)];
        let mut unlocked = self.flash.unlocked();
        (first..first + 3).try_for_each(|sector| unlocked.erase(sector))
    }

    fn write(&mut self, slot: usize, offset: usize, data: &[u8]) -> Result<(), Error> {
        if offset + data.len() > SLOT_BYTES {
            return Err(Error::ProgrammingSequence);
        }
        self.flash
            .unlocked()
            .program(Self::base(slot) + offset, data.iter())
    }

    fn read(&self, slot: usize) -> &[u8] {
        let base = Self::base(slot);
        &self.flash.read()[base..base + SLOT_BYTES]
    }
}
