//! `et-host`: everything et runs on the computer.
//!
//! Modules:
//!
//! - [`tables`]: a protocol's tables (SPEC §4) as plain data for people and programs, behind
//!   `et protocol`.
//! - [`recording`]: the recording format (JSON Lines: header, then one frame per line), which
//!   Python and MATLAB read without et; `et sim` writes it.
//! - [`learn`]: touch classification from raw voltages (SPEC §9): collection, QDA/LDA fitting
//!   with shrinkage, cross-validation, export to the firmware's model blob.
//! - [`link`]: the serial link to the firmware: packet decoding with resync and counters,
//!   commands with replies and timeouts, model upload, reconnect after a pulled cable.
//! - [`live`]: live touch sensing from any source (simulator, recording, board): images,
//!   touch events, frame-rate / SNR / BVC monitoring; behind `et view` and `et stream`.
//! - [`mesh`]: triangle meshes of a sheet with electrodes on the boundary (spade).
//! - [`fem`]: the forward model, P1 finite elements with the complete electrode model (SPEC §5).
//! - [`recon`]: one-step Gauss-Newton difference imaging with NOSER, ROIs, SPEC §7 metrics.
//! - [`imaging`]: the imaging pipeline strung together (set-up, a scene's simulated frames,
//!   pictures), as `et reconstruct` and `et demo` use it.
//! - [`dynamic`]: dynamic protocol selection (SPEC §8) as a state machine over the ROIs.
//! - [`demo`]: `et demo`, the whole method on the simulated sheet into a report folder.
//! - `viewer` (cargo feature `viewer`): `et view`, the egui window over [`live`].
//! - [`plot`]: PNG charts and heat maps with a colour bar.
#![forbid(unsafe_code)]

pub mod demo;
pub mod dynamic;
pub mod fem;
pub mod imaging;
pub mod learn;
pub mod link;
pub mod live;
pub mod mesh;
pub mod plot;
pub mod recon;
pub mod recording;
pub mod tables;
#[cfg(feature = "viewer")]
pub mod viewer;
