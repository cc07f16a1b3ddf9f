//! `et-host`: the application on the computer. It owns the serial link to the board,
//! recordings, live sensing, the demo, the viewer, plots and the `et` command-line program
//! (`src/bin/et/`); imaging is `et-recon`'s and learning `et-learn`'s, and this crate only
//! wires them to files, ports, windows and terminals.
//!
//! Modules, from the wire to the screen:
//!
//! - [`link`]: the serial link to the firmware: packet decoding with resync and counters,
//!   commands with replies and timeouts, model upload, reconnect after a pulled cable.
//! - [`recording`]: the recording format (JSON Lines: header, then one frame per line), which
//!   Python and MATLAB read without et; `et sim` and `et record` write it.
//! - [`frames`]: measured frames from other systems' files (CSV, `.npy`, `.npz`) for imaging.
//! - [`recorder`]: `et record`: frames from a board into recording parts, through pulled
//!   cables, idle boards and damaged frames.
//! - [`output`]: where commands write: never onto an input, never over an existing file
//!   without `--force`, complete files only (written aside, then renamed).
//! - [`message`]: an error and its causes as the one line `et` prints.
//! - [`tables`]: a protocol's tables (docs/method.md §4) as plain data, behind `et protocol`.
//! - [`live`]: live touch sensing from any source (simulator, recording, board): images,
//!   touch events, frame-rate / SNR / BVC monitoring; behind `et view` and `et stream`.
//! - [`demo`]: `et demo`, the whole method on the simulated sheet into a report folder.
//! - [`plot`]: PNG charts, heat maps with a colour bar, images of the sheet.
//! - `viewer` (cargo feature `viewer`): `et view`, the egui window over [`live`].
#![forbid(unsafe_code)]

pub mod demo;
pub mod frames;
pub mod link;
pub mod live;
pub mod message;
pub mod output;
pub mod pace;
pub mod pairs;
pub mod plot;
pub mod recorder;
pub mod recording;
pub mod tables;
#[cfg(feature = "viewer")]
pub mod viewer;
