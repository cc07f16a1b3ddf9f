//! et-recon's tests of its public interface, one binary (each module is one of the library's).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

mod background;
mod exact;
mod fem;
mod frame;
mod gcv;
mod greit;
mod mesh;
mod mesh_import;
mod panels;
mod pixels;
mod prior;
mod redundancy;
mod segment;
mod select;
mod touches;
