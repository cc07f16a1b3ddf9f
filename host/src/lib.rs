//! `et-host`: everything et runs on the computer.
//!
//! Modules (more arrive with their issues: `link`, `mesh`, `fem`, `recon`, `learn`, `viewer`):
//!
//! - [`tables`]: a protocol's tables (SPEC §4) as plain data for people and programs, behind
//!   `et protocol`.
#![forbid(unsafe_code)]

pub mod tables;
