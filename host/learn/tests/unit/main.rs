//! et-learn's tests of its public interface, one binary (each module is one of the library's).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

mod analysis;
mod core;
mod gp;
mod mlp;
mod model;
mod npz;
mod reference;
mod regress;
mod tabular;
