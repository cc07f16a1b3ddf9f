//! Why a reconstruction could not be set up or run: each fault with its numbers.

/// Why a reconstruction could not be set up or run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReconError {
    /// A number out of its range (alpha not finite or <= 0, s outside [0, 1], a GREIT radius
    /// or noise figure).
    #[error("reconstruction: {name} = {value}: must be {range}")]
    OutOfRange {
        /// What the number is (with its unit when it has one).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        range: &'static str,
    },
    /// A whole number out of its range (triangles, iterations, pixels).
    #[error("reconstruction: {name} = {value}: must be a whole number from {lo} to {hi}")]
    CountOutOfRange {
        /// What is counted.
        name: &'static str,
        /// The value given.
        value: usize,
        /// The least it may be.
        lo: usize,
        /// The most it may be.
        hi: usize,
    },
    /// A vector of frame values (K of them) of another length.
    #[error(
        "reconstruction: {what}: {got} values for K = {k}{}",
        et_core::schedule::other_frame_len(*got, *k)
            .map_or_else(String::new, |may| format!(" (of another protocol? {may})"))
    )]
    FrameLength {
        /// Which vector (the frame, the reference, the noise variances, the weights).
        what: &'static str,
        /// Its length.
        got: usize,
        /// The protocol's frame length.
        k: usize,
    },
    /// Tables of the mesh or the image that disagree in size.
    #[error("reconstruction: {what}: {got}, where {expected} belong")]
    Size {
        /// What was counted (a prior's values per triangle, a Jacobian's triangles, ...).
        what: &'static str,
        /// How many were given.
        got: usize,
        /// How many the mesh or the image has.
        expected: usize,
    },
    /// A weight or prior value that is not positive and finite.
    #[error("reconstruction: {what} {index} is {value}: each must be positive and finite")]
    NotPositive {
        /// What the values are.
        what: &'static str,
        /// The first bad one's index.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A name that is none of its choices (an alpha rule, a weighting).
    #[error("reconstruction: {what} '{given}': {choices}")]
    UnknownName {
        /// What was named.
        what: &'static str,
        /// The name given.
        given: String,
        /// The names there are.
        choices: &'static str,
    },
    /// A request the chosen method or rule cannot carry out.
    #[error("reconstruction: {0}")]
    Unsupported(&'static str),
    /// No candidate alpha to choose from.
    #[error("reconstruction: no candidate alpha")]
    NoCandidates,
    /// The reference frames cannot give V_0 (none, or of different lengths).
    #[error("reconstruction: reference: {0}")]
    Reference(#[source] et_core::stats::StatsError),
    /// GREIT's desired image's radius is over half the sheet.
    #[error(
        "reconstruction: a desired image's radius of {:.1} mm on a sheet {:.1} mm across: at \
         most half of it (GREIT's targets are small, 5 % of the sheet by default)",
        radius * 1e3,
        across * 1e3
    )]
    RadiusTooLarge {
        /// The radius, m.
        radius: f64,
        /// The sheet's longer side, m.
        across: f64,
    },
    /// A mesh made elsewhere with another electrode count than the sheet's.
    #[error("the mesh has {mesh} electrodes, the sheet {sheet}")]
    MeshElectrodes {
        /// The mesh's.
        mesh: usize,
        /// The sheet's.
        sheet: usize,
    },
    /// A mesh made elsewhere with a node off the scene's sheet (a mesh in mm, or another
    /// sheet's).
    #[error(
        "the mesh is not the sheet's: its node {node} at ({:.1}, {:.1}) mm lies outside the \
         scene's sheet, {:.1} x {:.1} mm (a mesh's coordinates are in metres)",
        at[0] * 1e3,
        at[1] * 1e3,
        sheet[0] * 1e3,
        sheet[1] * 1e3
    )]
    MeshNodeOffSheet {
        /// The node's index.
        node: usize,
        /// Where it is, m.
        at: [f64; 2],
        /// The sheet's width and height, m.
        sheet: [f64; 2],
    },
    /// A mesh made elsewhere that spans less than the scene's sheet.
    #[error(
        "the mesh is not the sheet's: it spans x {:.1} to {:.1} mm and y {:.1} to {:.1} mm, \
         the scene's sheet x {:.1} to {:.1} mm and y {:.1} to {:.1} mm",
        mesh[0] * 1e3,
        mesh[2] * 1e3,
        mesh[1] * 1e3,
        mesh[3] * 1e3,
        sheet[0] * 1e3,
        sheet[2] * 1e3,
        sheet[1] * 1e3,
        sheet[3] * 1e3
    )]
    MeshExtent {
        /// The mesh's bounding box [x0, y0, x1, y1], m.
        mesh: [f64; 4],
        /// The sheet's, m.
        sheet: [f64; 4],
    },
    /// The forward model failed (a conductivity or schedule it cannot take).
    #[error(transparent)]
    Forward(#[from] crate::fem::FemError),
    /// The data-space system is not positive definite (a Jacobian with NaN, or all zero).
    #[error("reconstruction: the regularised system is singular")]
    Singular,
    /// A frame holds NaN or infinite values.
    #[error("reconstruction: a frame value is NaN or infinite")]
    NonFinite,
    /// Iterative Gauss-Newton found no step that lowers its objective at this iteration
    /// (the linearisation does not describe the data: a smaller alpha than the data bear, or
    /// a model far from the sheet).
    #[error(
        "iterative Gauss-Newton: no step lowers the misfit at iteration {iteration}; \
                 try a larger alpha"
    )]
    NoDescent {
        /// The iteration (0-based).
        iteration: usize,
    },
}
