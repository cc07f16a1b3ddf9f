//! et-host's library tests through its public interface, one binary (each module is one of
//! the library's).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

mod demo;
mod eidors;
mod frames;
mod link;
mod live;
mod message;
mod output;
mod pace;
mod pairs;
mod plot;
mod recording;
mod tables;
#[cfg(feature = "viewer")]
mod viewer;
