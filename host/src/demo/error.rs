//! Why the demo stopped: the stage, and the library's own error under it.

use std::path::{Path, PathBuf};

use et_core::config::ConfigError;
use et_core::protocol::ProtocolError;
use et_learn::dataset::DataError;
use et_learn::fit::FitError;
use et_learn::model::UseError;
use et_learn::{TrainError, collect::CollectError, model_file::ModelFileError};
use et_recon::{ImagingError, ReconError, fem::FemError, mesh::MeshError};
use et_sim::scene::{FieldError, SceneError};
use et_sim::sheet::SheetError;
use et_sim::still::StillError;

use crate::output::OutputError;
use crate::plot::PlotError;

/// The demo's results.
pub(super) type Result<T> = std::result::Result<T, DemoError>;

/// Why `et demo` stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DemoError {
    /// One of the three stages failed (the stage, then why).
    #[error("{stage}: {source}")]
    Stage {
        /// "touch classification", "imaging the reference scenarios" or "the speed/accuracy sweep".
        stage: &'static str,
        /// Why.
        source: Box<DemoError>,
    },
    /// A file or folder could not be created, written or removed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The output folder may not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A built-in scene does not parse or simulate.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A built-in scene's value is out of range.
    #[error(transparent)]
    Field(#[from] FieldError),
    /// A built-in sheet cannot be built.
    #[error(transparent)]
    Sheet(#[from] SheetError),
    /// A scene's frames could not be simulated.
    #[error(transparent)]
    Still(#[from] StillError),
    /// A built-in protocol is refused.
    #[error(transparent)]
    Protocol(#[from] ProtocolError),
    /// A built-in protocol's schedule is refused.
    #[error(transparent)]
    Schedule(#[from] et_core::schedule::ScheduleError),
    /// A built-in scan configuration is refused.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// Collecting a dataset failed.
    #[error(transparent)]
    Collect(#[from] CollectError),
    /// Datasets could not be joined or featurised.
    #[error(transparent)]
    Data(#[from] DataError),
    /// A model could not be fitted or exported.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// A trained model could not be tested.
    #[error(transparent)]
    Use(#[from] UseError),
    /// Training failed.
    #[error(transparent)]
    Train(#[from] TrainError),
    /// A model file could not be written.
    #[error(transparent)]
    ModelFile(#[from] ModelFileError),
    /// Setting up a reconstruction or imaging a frame failed.
    #[error(transparent)]
    Imaging(#[from] ImagingError),
    /// A sheet could not be meshed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A forward model could not be built or solved.
    #[error(transparent)]
    Fem(#[from] FemError),
    /// An iterative fit failed.
    #[error(transparent)]
    Recon(#[from] ReconError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The summary could not be serialised.
    #[error("summary: {0}")]
    Json(#[from] serde_json::Error),
    /// The demo's own scenes disagree (a bug in the built-in scene set).
    #[error("{0}")]
    Scenes(&'static str),
}

/// Names the stage a result came from.
pub(super) trait Staged<T> {
    /// The error, under the stage's name.
    fn stage(self, stage: &'static str) -> Result<T>;
}

impl<T> Staged<T> for Result<T> {
    fn stage(self, stage: &'static str) -> Result<T> {
        self.map_err(|e| DemoError::Stage {
            stage,
            source: Box::new(e),
        })
    }
}

/// The I/O error, with the path it was about.
pub(super) fn io(path: impl AsRef<Path>) -> impl FnOnce(std::io::Error) -> DemoError {
    let path = path.as_ref().to_path_buf();
    move |source| DemoError::Io { path, source }
}
