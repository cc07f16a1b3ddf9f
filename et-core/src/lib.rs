//! `et-core`: the part of et that runs everywhere, on the microcontroller as on the host.
//! `no_std`, no allocation: every buffer is the caller's.
//!
//! Modules in pipeline order:
//!
//! - [`protocol`]: injection / measurement tables of docs/method.md §4 (adjacent, pseudo-polar, PP-PP,
//!   opposite, and the general drive skip / measure skip form), selection masks, frame length
//!   K, reciprocity-deduplicated feature sets, mux control words.
//! - [`config`]: [`ScanConfig`], the one value that says how a scan is acquired.
//! - [`frontend`]: the [`Frontend`] trait, the only hardware seam, and [`frontend::MuxLines`]
//!   driving the muxes through embedded-hal 1.0.
//! - [`extract`]: settle-then-median for one burst (Algorithm 1) and sub-section medians
//!   (Algorithms 2-3).
//! - [`scan`]: the scan engine, one protocol scan through a `Frontend` into V_m.
//! - [`wire`]: [`wire::Frame`], [`wire::Command`], [`wire::Event`] in postcard + CRC-32 + COBS
//!   packets, and the resynchronising [`wire::Accumulator`].
//! - [`device`]: the firmware's logic without its hardware: commands, model upload into two
//!   slots with verification, frames, on-chip classification, health counters.
//! - [`emulated`]: a sheet given by transfer impedances, the `Frontend` of the QEMU image.
//! - [`model`]: QDA / LDA evaluation over a validated model blob the caller owns (docs/method.md §9).
//! - [`stats`]: SNR, MAD (docs/method.md §3) and BVC (docs/method.md §7).
//! - [`board`]: the constants the board and the host share (baud rate, model slot size).
//! - `sheet` (feature `std`): the physical sheet, outline, fabric and electrodes, as the
//!   simulator and the reconstruction both describe it.
//! - `schedule` (feature `std`): a frame's measurements as any EIT system lists them (source,
//!   sink, positive, negative, current per value), from a built-in protocol or a CSV file.
//! - `text` (feature `std`): tables as users' tools write them (delimiter, quotes, decimal
//!   commas), read for every et reader of tables.
//! - `said` (feature `std`): parsers' messages (serde's type names) in the words of a file's author.
//! - [`rng`]: the one seedable pseudo-random generator (simulator, QEMU sheet, folds, tests).
//! - [`precision`], [`time`]: binary16 storage and the injected clock.
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![deny(missing_docs)]

pub mod board;
pub mod config;
pub mod device;
pub mod emulated;
pub mod extract;
pub mod frontend;
pub mod model;
pub mod precision;
pub mod protocol;
pub mod rng;
#[cfg(feature = "std")]
pub mod said;
pub mod scan;
#[cfg(feature = "std")]
pub mod schedule;
#[cfg(feature = "std")]
pub mod sheet;
pub mod stats;
#[cfg(feature = "std")]
pub mod text;
pub mod time;
pub mod whole;
pub mod wire;

pub use config::ScanConfig;
pub use frontend::{AdcScale, Frontend};
pub use protocol::{ElectrodeId, Halving, Injection, Measurement, Protocol, ProtocolKind};
pub use scan::{ScanReport, Scanner};
pub use time::Micros;
