//! The board: pin map and clocks of the STM32F405 that drives the mux PCB (SPEC §2).
//!
//! | signal | pin | notes |
//! | --- | --- | --- |
//! | source mux A0..A3, EN | PC0..PC3, PC4 | ADG1606 #1, to the Howland current source |
//! | sink mux A0..A3, EN | PC5..PC8, PC9 | ADG1606 #2, to ground |
//! | serial TX / RX | PA2 / PA3 (USART2) | to the host, 921 600 baud, 8N1 |
//! | status LED | PA5 | toggles with every status event |
//! | PGIA output to ADC | PA0 (ADC1 IN0) | sampling arrives with the firmware issue |
//!
//! The mux lines are driven by `et_core::frontend::MuxLines` (break-before-make, settle delay):
//! the firmware only hands it the pins.

use stm32f4xx_hal::gpio::{AnyPin, Output};

/// Serial link speed. At 921 600 baud (92 160 bytes/s) an adjacent frame at L = 16 (about
/// 860 bytes) leaves room for 107 frames/s against the 78 Hz reference rate.
pub const BAUD: u32 = 921_600;

/// Settling wait after a mux switch, in ns: the PGIA settles in about 8 us (SPEC §2).
pub const MUX_SETTLE_NS: u32 = 8_000;

/// System clock: HSI (16 MHz internal, no crystal needed) through the PLL.
pub const SYSCLK_HZ: u32 = 168_000_000;

/// How often a status event goes out, in ms.
pub const STATUS_PERIOD_MS: u32 = 500;

/// One mux control line.
pub type MuxPin = AnyPin<Output>;
