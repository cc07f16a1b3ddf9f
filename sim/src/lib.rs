//! `et-sim`: the emulated fabric sheet that every test and the demo run against.
//!
//! Modules, from geometry to sensor:
//!
//! - [`network`]: the sheet as a resistor network with electrode contacts, factored once into
//!   the electrodes' transfer impedance (deliberately not the host's finite elements).
//! - [`band`]: the banded Cholesky the network is solved with.
//! - [`touch`]: touches, the piezoresistive law, and the conductance change they make.
//! - [`fast`]: the fast path, a precomputed network updated per touch state (Woodbury).
//! - [`sheet`]: the simulated sheet (the physical `et_core::sheet::Sheet`, and the
//!   simulator's grid, piezo law and bend) built into a network; noiseless frames for any
//!   protocol, with the current source's compliance.
//! - [`frontend`]: the acquisition chain as an `et_core::Frontend` (current jitter, settling,
//!   noise, gain, ADC), and the fast path for whole noisy frames.
//! - [`calibration`]: the front end's noise fitted to the reference hardware's SNR and MAD.
//! - [`scene`]: scene files (TOML) and the runner that turns them into frames with their truth;
//!   [`scenes`]: the scenes compiled in (the default sheet, the reference scenarios).
//! - [`foreign`]: another lab's instrument: any schedule on the network, with its noise and
//!   drift.
//! - [`still`]: a still scene's frames (V_0, the noise of dV, one touched frame), as imaging
//!   uses them.
//! - [`emulated`]: the tables of the sheet compiled into the firmware's QEMU image.
//!
//! It depends on `et-core` only.
#![forbid(unsafe_code)]

pub mod band;
pub mod calibration;
pub mod emulated;
pub mod fast;
pub mod foreign;
pub mod frontend;
pub mod network;
pub mod scene;
pub mod scenes;
pub mod sheet;
pub mod still;
pub mod touch;
