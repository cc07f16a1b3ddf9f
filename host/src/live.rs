//! Live touch sensing from any source: frames in, images and touch events out. The viewer
//! (`et view`) and `et stream` are both thin shells over this module.
//!
//! - [`Source`]: where frames come from, a simulated scene (which a pointer can press), a
//!   recording (replay with pause and seek) or a board on a serial port.
//! - [`Processor`]: V_0 from the first untouched frames, then per frame dV = V_m - V_0, the
//!   one-step image onto a pixel grid (docs/method.md §6), its touches (regions split at their saddles),
//!   and a [`TouchEvent`] when a touch stands out of the image's noise; with a trained model also the class,
//!   its posterior and the posterior-weighted position (docs/method.md §9, §11).
//! - [`Monitor`]: frame rate, per-channel SNR and BVC over time, and lost frames.

use std::collections::VecDeque;
use std::path::Path;
use std::time::{Duration, Instant};

use et_core::ScanConfig;
use et_core::protocol::ProtocolKind;
use et_core::stats;
use et_core::wire::{Command, Event, Uplink};
use et_sim::scene::{Detail, Run, Scene};
use et_sim::sheet::SheetSpec;
use et_sim::touch::Touch;
use nalgebra::DMatrix;
use serde::Serialize;

use crate::link::{Counters, Link};
use crate::recording::{self, Recording};
use et_learn::fit::Fitted;
use et_learn::model_file::ModelFile;
use et_learn::regress::posterior_centre;
use et_recon::Imager;
use et_recon::mesh::Mesh;
use et_recon::onestep::noise_sd;
use et_recon::{OneStep, PROMINENCE, PixelGrid, Region, above_noise, default_threshold, touches};

mod monitor;
mod processor;
mod source;

pub use monitor::Monitor;
pub use processor::{Classifier, Output, Processor, Settings, TouchEvent};
pub use source::{
    Health, PortSource, ReplaySource, SimSource, Source, SourceSpec, default_scene, open_source,
};

/// One frame as the live pipeline sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveFrame {
    /// Sequence number (gaps: frames lost).
    pub seq: u32,
    /// Device time of the scan, us.
    pub t_us: u32,
    /// What produced it.
    pub config: ScanConfig,
    /// V_m, V (K values).
    pub voltages: Vec<f32>,
    /// The true touches, when the source knows them (simulated or recorded from the sim).
    pub truth: Option<Vec<Touch>>,
    /// The board's own class for this frame (`Event::Touch`) and its margin.
    pub chip_class: Option<(u16, f32)>,
}

/// The protocols the live pipeline offers, plus automatic selection (docs/method.md §8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProtocolChoice {
    /// One protocol.
    Fixed(ProtocolKind),
    /// `dynamic::Selector` picks from the regions.
    Automatic,
}

#[cfg(test)]
pub(crate) mod tests;
