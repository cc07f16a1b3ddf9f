//! Why a forward solve failed: each fault with its numbers.

use super::MIN_CONTACT_RATIO;

/// Why a forward solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FemError {
    /// A count that is not the mesh's or the model's (impedances per electrode,
    /// conductivities per triangle, currents' rows per electrode, a protocol's electrodes).
    #[error("forward model input: {got} {what} for {expected} {of}")]
    Count {
        /// What was counted.
        what: &'static str,
        /// How many were given.
        got: usize,
        /// How many there must be.
        expected: usize,
        /// What they are counted against.
        of: &'static str,
    },
    /// A value that must be finite and positive (a contact impedance, a conductivity).
    #[error("forward model input: {what} {index} is {value}: it must be finite and > 0")]
    NotPositive {
        /// What the value is.
        what: &'static str,
        /// Whose (the electrode's or triangle's index).
        index: usize,
        /// The value.
        value: f64,
    },
    /// Fewer than two electrodes.
    #[error("forward model input: at least 2 electrodes")]
    TooFewElectrodes,
    /// An electrode of a single node under a model that needs edges.
    #[error(
        "forward model input: electrode {electrode} is a single node (a point electrode): \
         image with electrodes.model = \"point\""
    )]
    PointElectrode {
        /// The electrode.
        electrode: usize,
    },
    /// A triangle of no area.
    #[error("forward model input: triangle {triangle} is degenerate")]
    Degenerate {
        /// The triangle.
        triangle: usize,
    },
    /// A node under two electrodes (point or shunt models).
    #[error("forward model input: node {node} belongs to electrodes {} and {}", electrodes[0], electrodes[1])]
    SharedNode {
        /// The node.
        node: usize,
        /// The two electrodes.
        electrodes: [usize; 2],
    },
    /// Contact impedances given to a model without them.
    #[error("forward model input: contact impedances are the complete electrode model's")]
    NotComplete,
    /// A current that is NaN or infinite.
    #[error("forward model input: the currents must be finite")]
    NonFiniteCurrent,
    /// A current pattern that does not sum to zero.
    #[error("forward model input: pattern {pattern}: currents do not sum to 0")]
    Unbalanced {
        /// The pattern (column).
        pattern: usize,
    },
    /// A protocol that measures on a drive electrode under point electrodes.
    #[error(
        "forward model input: value {value} measures on drive electrode {electrode}: point \
         electrodes cannot model it (use the complete electrode model, electrodes.model = \
         \"complete\")"
    )]
    MeasuresOnDrive {
        /// The frame value.
        value: usize,
        /// The electrode.
        electrode: usize,
    },
    /// An image grid of too few or too many pixels across.
    #[error("forward model input: {pixels} pixels across: use 4 to {max}")]
    Pixels {
        /// The pixels asked for.
        pixels: usize,
        /// The most there may be.
        max: usize,
    },
    /// The system could not be factorised (disconnected mesh, or values so extreme that it
    /// is not numerically positive definite).
    #[error(
        "forward model: factorisation failed: the finite-element system is singular or not \
         positive definite (conductivities that span too many powers of ten, or a piece of the \
         mesh that no electrode reaches)"
    )]
    Factorisation,
    /// The solve gave potentials that are not finite.
    #[error("forward model: factorisation failed: non-finite potentials")]
    NonFinitePotentials,
    /// The complete model's contact resistance is too small against the sheet's
    /// ([`MIN_CONTACT_RATIO`]).
    #[error("contact resistance {contact_ohm:e} ohm is too small for the complete electrode \
                 model on a sheet of {sheet_ohm:e} ohm/sq (under {MIN_CONTACT_RATIO:e} of it, its \
                 system cannot be solved accurately): give sheet.electrodes.contact_ohm >= {:e}, \
                 or model = \"shunt\" for ideal contacts", MIN_CONTACT_RATIO * .sheet_ohm)]
    ContactTooSmall {
        /// The contact resistance, ohm.
        contact_ohm: f64,
        /// The sheet resistance, ohm per square.
        sheet_ohm: f64,
    },
}
