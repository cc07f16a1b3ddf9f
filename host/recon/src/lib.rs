//! `et-recon`: imaging a sheet from its boundary voltages. It owns the meshes, the forward
//! model, the reconstruction and what is read off an image; it has no command line, no file
//! formats of its own beyond mesh import, and no plotting.
//!
//! The entry point is [`Reconstructor`]: set up once from a [`Spec`] (sheet, protocol, mesh,
//! method, alpha rule), then [`Reconstructor::image`] for every frame. The modules below are
//! its stages, in pipeline order (section numbers refer to `docs/method.md`):
//!
//! - [`mesh`]: triangle meshes of a sheet with electrodes on the boundary (spade), refined at
//!   regions of interest; [`mesh::import`] reads Gmsh and CSV meshes.
//! - [`fem`]: the forward model (§5), P1 finite elements with the complete electrode model or
//!   point electrodes, the Jacobian by the adjoint method.
//! - [`imager`]: one sheet's forward model at its background and its pixel grid, the set-up
//!   every caller shares.
//! - [`onestep`]: one-step Gauss-Newton with the NOSER prior (§6), the reconstruction matrix
//!   and the noise it carries from dV to each pixel.
//! - [`gcv`]: alpha by generalised cross-validation (§6.3).
//! - [`greit`]: GREIT, the consensus linear reconstruction onto pixels, and its figures of
//!   merit over a grid of targets (§6.6).
//! - [`gauss_newton`]: iterative Gauss-Newton (§6.4).
//! - [`pixels`]: pixel grids over a mesh and the reconstruction onto them in thin factors.
//! - [`touches`]: regions of interest and touches, split at their saddles and kept above
//!   their noise (§6.5).
//! - [`segment`]: the three-class picture (background, resistive, conductive) from the objects.
//! - [`metrics`]: the image metrics SE, PE, RNG and BVC against the truth (§7).
//! - [`reconstructor`]: the entry point, the stages above as one set-up and one call a frame.
//! - [`select`]: choosing the protocol from the image (§8), as a state machine.
//!
//! The simulator is not a dependency (the sheet's description is `et_core::sheet`), so tests
//! against simulated frames (in `tests/tests/imaging`) do not commit the inverse crime.
#![forbid(unsafe_code)]

pub mod background;
pub mod exact;
pub mod fem;
pub mod gauss_newton;
pub mod gcv;
pub mod greit;
pub mod imager;
pub mod limits;
pub mod mesh;
pub mod metrics;
pub mod onestep;
pub mod operator;
pub mod pixels;
pub mod reconstructor;
pub mod redundancy;
pub mod segment;
pub mod select;
pub mod touches;

pub use gauss_newton::{Data, Fit, GaussNewton, Iterate, Stop, gauss_newton};
pub use gcv::{default_alphas, gcv_alpha};
pub use greit::{Greit, GreitOptions, Regularisation};
pub use imager::Imager;
pub use metrics::{Merit, Metrics, TouchMatch, match_touches, merit, metrics};
pub use onestep::{DataSpace, OneStep, ReconError};
pub use operator::{FrameOperator, SquaredRows};
pub use pixels::{PixelGrid, PixelOperator};
pub use reconstructor::{
    AlphaRule, Found, FrameNoise, FrameObjects, FramePixels, Image, ImagingError, MeshPlan, Method,
    NoiseSource, Reconstructor, Reference, ReferenceChanges, Spec,
};
pub use segment::{Class, SEGMENT_LEVEL, segment};
pub use touches::{
    Object, PROMINENCE, PixelNoise, Region, TOUCH_Z, above_noise, default_threshold, objects,
    objects_with, regions, touch_rule, touches,
};
