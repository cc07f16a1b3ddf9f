//! `et-sim`: the emulated fabric sheet.
//!
//! Its resistor-network model of the sheet (deliberately not the host's finite elements),
//! touches, electrodes, front end and noise arrive with the sim issue; the crate exists now so
//! that the workspace has the shape DESIGN.md fixes. It depends on `et-core` only.
#![forbid(unsafe_code)]
