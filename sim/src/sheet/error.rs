//! Why a sheet cannot be built.

use super::*;

/// Why a sheet cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SheetError {
    /// The sheet's description: its outline, or a field out of range (one of the physical
    /// sheet's, or the simulator's own: grid, piezo law, bend, front end).
    #[error(transparent)]
    Spec(#[from] et_core::sheet::SheetError),
    /// The network could not be built or solved.
    #[error("sheet: {0}")]
    Network(NetworkError),
    /// The grid would have more nodes than the simulator keeps.
    #[error(
        "sheet.resolution: {spacing} m gives about {nodes:.0} grid nodes; the simulator keeps \
         the untouched network's inverse (nodes x nodes), so at most {MAX_GRID_NODES}: use a \
         coarser spacing{}",
        if *default { " (the default follows the electrode width: set sheet.resolution)" } else { "" }
    )]
    TooManyNodes {
        /// The grid spacing, m.
        spacing: f64,
        /// The nodes it gives (about).
        nodes: f64,
        /// Whether the spacing is the default one.
        default: bool,
    },
    /// Electrodes moved along the outline (a scene's `movement.rms`, `et collect
    /// --movement-mm`) so far that two overlap or pass each other: their numbering would no
    /// longer be their order on the sheet.
    #[error(
        "movement: electrodes {a} and {b}, moved {moved_a:.1} and {moved_b:.1} mm along the \
         outline, {} ({width_mm:.1} mm wide, {spacing_mm:.1} mm apart): the movement's rms is \
         too large for this spacing (a few per cent of it, as clips put back by hand)",
        if *crossed { "pass each other" } else { "overlap" }
    )]
    Moved {
        /// One electrode (0-based).
        a: usize,
        /// Its neighbour on the outline.
        b: usize,
        /// How far each moved, mm.
        moved_a: f64,
        /// How far the neighbour moved, mm.
        moved_b: f64,
        /// Whether they passed each other (else they overlap).
        crossed: bool,
        /// The electrodes' width, mm.
        width_mm: f64,
        /// Their nominal spacing, mm (the outline over the count).
        spacing_mm: f64,
    },
    /// A touch smaller than the grid resolves ([`SheetSpec::check_touch`]).
    #[error(
        "touch[{touch}].radius: {radius} m is under half the simulator's grid spacing \
         ({spacing} m), so its frames would depend on where it falls between the grid's nodes: \
         set sheet.resolution to at most {} m (twice the radius), or image it with et forward \
         (the finite elements refine at each touch)", 2.0 * .radius
    )]
    Unresolved {
        /// The touch's index in the scene.
        touch: usize,
        /// Its radius, m.
        radius: f64,
        /// The grid spacing, m.
        spacing: f64,
    },
}

impl SheetError {
    /// `field` (as a scene file names it) is out of range: `fault`.
    #[must_use]
    pub fn field(field: &'static str, fault: FieldFault) -> Self {
        Self::Spec(et_core::sheet::SheetError::Field { field, fault })
    }

    /// `field` (as a scene file names it) breaks `rule`.
    #[must_use]
    pub fn rule(field: &'static str, rule: &'static str) -> Self {
        Self::field(field, FieldFault::Rule(rule))
    }
}
