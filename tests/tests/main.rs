//! End-to-end and cross-crate tests: one binary, one module per theme.
//!
//! - `budget`: the serial link budget for every configuration the board supports.
//! - `e2e`: the pieces of `et-core` wired as firmware and host wire them: scan engine -> frames
//!   over a damaged byte stream -> host model fit -> model upload in chunks -> on-device
//!   classification -> touch events back. New end-to-end scenarios go here.
//! - `imaging`: et-recon's reconstructions of the simulator's frames: one-step and iterative
//!   Gauss-Newton, GREIT, GCV, touches, the finite elements against the resistor network.
//! - `qemu`: the real firmware image booted in QEMU, driven over a pty by the host link.

mod budget;
mod e2e;
mod imaging;
mod qemu;
