//! End-to-end and cross-crate tests: one binary, one module per theme.
//!
//! - `e2e`: the pieces of `et-core` wired as firmware and host wire them: scan engine -> frames
//!   over a damaged byte stream -> host model fit -> model upload in chunks -> on-device
//!   classification -> touch events back. New end-to-end scenarios go here.

mod e2e;
