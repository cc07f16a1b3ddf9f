//! The board's constants that the firmware and the host must agree on: one definition, used
//! by both (the firmware configures its USART and flash slots from them, the host opens the
//! port and sizes models with them).

/// Serial link speed, 8N1 (200 000 bytes/s). The busiest configuration the board can run
/// (L = 16, PP-PP, two measurements per step position, at 78 Hz) needs 66 % of it with its
/// touch events; the reference adjacent frame 36 %. At 921 600 baud the largest frames did not
/// fit (the link-budget test in `tests/`). USB-serial adapters with FT232R, FT232H, CP2102N or
/// CH340 chips run at 2 Mbaud; the STM32F405's USART1 clock (84 MHz) divides to it exactly.
pub const BAUD: u32 = 2_000_000;

/// Bytes of one model slot in the board's flash (three 128 KiB sectors).
pub const SLOT_BYTES: usize = 384 * 1024;

/// The largest model blob the board takes: one slot less the record of its commit at the
/// slot's end (`device::RECORD_BYTES`, what a restarted board restores it from). Uploads go
/// to the slot that is not in use, so a model blob must fit one slot.
pub const MODEL_SLOT_BYTES: usize = SLOT_BYTES - crate::device::RECORD_BYTES;

/// Bytes of one model slot in the firmware's QEMU image, in RAM (QEMU programs no flash).
pub const QEMU_SLOT_BYTES: usize = 16 * 1024;

/// The largest model blob the QEMU image takes (its slot less the commit record).
pub const QEMU_MODEL_SLOT_BYTES: usize = QEMU_SLOT_BYTES - crate::device::RECORD_BYTES;
