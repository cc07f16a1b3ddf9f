//! Why a mesh could not be made or read: [`MeshError`], each fault with its cause named.

use super::import;
use et_core::sheet::ShapeError;

/// Why a mesh could not be made or read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The sheet's outline is unusable.
    #[error(transparent)]
    Shape(#[from] ShapeError),
    /// Mesh sizes that are not finite and positive.
    #[error(
        "sizes must be finite and positive: interior {interior} m, at electrodes {electrode} m, \
         smallest angle {min_angle_deg} degrees"
    )]
    Sizes {
        /// The interior's edge, m.
        interior: f64,
        /// The edge at the electrodes, m.
        electrode: f64,
        /// The smallest angle, degrees.
        min_angle_deg: f64,
    },
    /// An electrode width that is not positive.
    #[error("electrode width must be positive")]
    ElectrodeWidth,
    /// No size gave a mesh near the triangles asked for.
    #[error("no mesh was made")]
    NoMesh,
    /// A refinement region with a centre that is not finite or a radius or edge that is not
    /// positive.
    #[error(
        "a refinement needs a finite centre and a positive radius and edge: centre ({}, {}) m, \
         radius {radius} m, edge {edge} m",
        centre[0],
        centre[1]
    )]
    Refinement {
        /// Its centre, m.
        centre: [f64; 2],
        /// Its radius, m.
        radius: f64,
        /// Its edge, m.
        edge: f64,
    },
    /// A refinement region that would add more points than a mesh is made of.
    #[error("a refinement of radius {radius} m at edge {edge} m adds over {limit} points")]
    RefinementTooFine {
        /// Its radius, m.
        radius: f64,
        /// Its edge, m.
        edge: f64,
        /// The limit it passes, in words.
        limit: &'static str,
    },
    /// A refinement region smaller than any frame can show.
    #[error(
        "a refinement of radius {} m is under 1e-4 of the sheet's size ({} m): it changes no \
         frame that single precision resolves (is the radius in mm?)",
        et_core::said::Sig(*.radius), et_core::said::Sig(*.least)
    )]
    RefinementTooSmall {
        /// Its radius, m.
        radius: f64,
        /// The least radius, m.
        least: f64,
    },
    /// A refinement region that does not meet the sheet.
    #[error(
        "a refinement at ({}, {}) m of radius {radius} m does not meet the sheet",
        centre[0],
        centre[1]
    )]
    RefinementOffSheet {
        /// Its centre, m.
        centre: [f64; 2],
        /// Its radius, m.
        radius: f64,
    },
    /// Two electrodes overlap on the outline.
    #[error("electrodes {electrode} and the next overlap on the outline")]
    Overlap {
        /// The first of the two.
        electrode: usize,
    },
    /// The triangulation failed (a degenerate outline): why, in words.
    #[error("triangulation failed: {0}")]
    Triangulation(&'static str),
    /// An electrode has no boundary edge.
    #[error("electrode {electrode} covers no boundary edge")]
    EmptyElectrode {
        /// Which.
        electrode: usize,
    },
    /// A mesh of no triangles.
    #[error("no triangles")]
    NoTriangles,
    /// Fewer than two electrodes.
    #[error("{count} electrodes: need at least 2")]
    TooFewElectrodes {
        /// How many.
        count: usize,
    },
    /// A triangle names a node past the nodes.
    #[error("triangle {triangle} names a node past the {nodes} nodes")]
    TriangleNodePast {
        /// The triangle.
        triangle: usize,
        /// How many nodes there are.
        nodes: usize,
    },
    /// An electrode names a node past the nodes.
    #[error("an electrode names a node past the {nodes} nodes")]
    ElectrodeNodePast {
        /// How many nodes there are.
        nodes: usize,
    },
    /// A triangle of (nearly) no area.
    #[error("triangle {triangle} is degenerate (area {area:.3e} m^2)")]
    Degenerate {
        /// The triangle.
        triangle: usize,
        /// Its area, m^2.
        area: f64,
    },
    /// An electrode given as a single node and as edges at once.
    #[error(
        "electrode {electrode} mixes a single node with edges: give one node (a point \
         electrode) or its nodes in order along the boundary"
    )]
    MixedElectrode {
        /// The electrode.
        electrode: usize,
    },
    /// Two electrodes that share a node (and so are shorted together).
    #[error(
        "electrodes {} and {} share node {node}: electrodes that touch are one electrode \
         (leave a gap of at least one edge)",
        electrodes[0],
        electrodes[1]
    )]
    SharedNode {
        /// The two electrodes.
        electrodes: [usize; 2],
        /// The node.
        node: usize,
    },
    /// A triangle listed twice.
    #[error("triangle {triangle} repeats triangle {first}")]
    RepeatedTriangle {
        /// The repeat.
        triangle: usize,
        /// The first listing.
        first: usize,
    },
    /// Two triangles that cover the same corner of a node: they overlap.
    #[error(
        "triangles {} and {} overlap at node {node} (a triangle laid over others, or a fold): \
         the finite elements would add their conductances where they overlap",
        triangles[0],
        triangles[1]
    )]
    Overlapping {
        /// The two triangles, in file order.
        triangles: [usize; 2],
        /// A node both have, where their corners overlap.
        node: usize,
    },
    /// The boundary crosses itself where no node is shared: triangles lie over others.
    #[error(
        "the mesh's boundary crosses itself: its edge ({}, {}) meets its edge ({}, {}), which \
         share no node (a sheet meshed folded over itself, or pieces laid over each other): \
         the finite elements would add their conductances where they overlap",
        edges[0][0], edges[0][1], edges[1][0], edges[1][1]
    )]
    BoundaryCrossing {
        /// The two boundary edges (node pairs).
        edges: [[usize; 2]; 2],
    },
    /// A piece of the mesh that no electrode reaches.
    #[error(
        "triangle {triangle} is in a piece of the mesh that no electrode reaches ({triangles} \
         of its triangles): no current flows there, and the finite elements' system is \
         singular (join it to the sheet, or leave it out)"
    )]
    Floating {
        /// The piece's first triangle.
        triangle: usize,
        /// Its triangles.
        triangles: usize,
    },
    /// A node in no triangle.
    #[error("node {node} is in no triangle (an unused node leaves the system singular)")]
    UnusedNode {
        /// The node.
        node: usize,
    },
    /// A point electrode's node inside the mesh.
    #[error("electrode {electrode}: node {node} is inside the mesh, not on its boundary")]
    InteriorNode {
        /// The electrode.
        electrode: usize,
        /// Its node.
        node: usize,
    },
    /// An electrode's edge inside the mesh.
    #[error(
        "electrode {electrode}: edge ({}, {}) is inside the mesh, not on its boundary",
        edge[0],
        edge[1]
    )]
    InteriorEdge {
        /// The electrode.
        electrode: usize,
        /// The edge's nodes.
        edge: [usize; 2],
    },
    /// Consecutive electrode nodes that share no triangle edge.
    #[error(
        "electrode {electrode}: nodes {} and {} share no triangle edge (list an electrode's \
         nodes in order along the boundary)",
        nodes[0],
        nodes[1]
    )]
    NotAnEdge {
        /// The electrode.
        electrode: usize,
        /// The two nodes.
        nodes: [usize; 2],
    },
    /// A mesh file that cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        source: import::ReadError,
    },
    /// A file of another kind given as a mesh file: what it is, and what a mesh file is.
    #[error("{}: {said}; {}", path.display(), import::MESH_FILES)]
    NotMesh {
        /// The file.
        path: std::path::PathBuf,
        /// What it is.
        said: String,
    },
    /// A mesh file that is not a mesh at a line.
    #[error("{}:{line}: {fault}", path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// The line (1-based; 0 for the file as a whole).
        line: usize,
        /// What is wrong there.
        fault: import::FileFault,
    },
}
