//! What is wrong with a mesh file: the fault at a line, or why it could not be read.

/// What a mesh file is, said where another file came in its place.
pub const MESH_FILES: &str = "a mesh is a Gmsh 2.2 ASCII .msh file (gmsh -format msh22), or three \
     CSV files given together, nodes.csv,triangles.csv,electrodes.csv (each row a node's x, y \
     in m; a triangle's three node numbers, from 0; an electrode's boundary nodes)";

/// What is wrong at a line of a mesh file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FileFault {
    /// A CSV row of another width, or with a value that is not a number: what the row holds
    /// (`found` cells), and what each row of the file is (it said "expected 2 numbers" of a
    /// frame's 208 values).
    #[error("{found} cells, where each row is {what}")]
    Numbers {
        /// The row's cells.
        found: usize,
        /// What each row of the file is.
        what: &'static str,
    },
    /// A CSV row with a cell that is not a number.
    #[error("'{0}' is not a number (each row is an electrode's node numbers)")]
    NumberList(String),
    /// A coordinate that is NaN or infinite.
    #[error("non-finite coordinate")]
    NonFinite,
    /// A row of the wrong number of values.
    #[error("wrong number of values")]
    Width,
    /// A node number past the nodes file's.
    #[error("node {node}, but {} has {count} nodes (numbered from 0)", nodes.display())]
    NodePast {
        /// The node named.
        node: usize,
        /// The nodes file.
        nodes: std::path::PathBuf,
        /// Its nodes.
        count: usize,
    },
    /// No `$MeshFormat`.
    #[error("no $MeshFormat: not a Gmsh file; {MESH_FILES}")]
    NotGmsh,
    /// A Gmsh version other than 2.
    #[error("Gmsh format {version}: only 2.2 ASCII is read; save with `gmsh -format msh22`")]
    GmshVersion {
        /// The version as written.
        version: String,
    },
    /// A binary Gmsh file.
    #[error("binary Gmsh file: save as ASCII")]
    Binary,
    /// A section missing.
    #[error("no {0} section")]
    NoSection(&'static str),
    /// A node line that is not `id x y z`.
    #[error("node line: id x y z")]
    NodeLine,
    /// No count where one belongs.
    #[error("expected a count")]
    Count,
    /// A count the file has no lines for.
    #[error("{count} {what} claimed; the file has {room} lines after the count")]
    CountPastEnd {
        /// The count.
        count: usize,
        /// What is counted.
        what: &'static str,
        /// The lines there are.
        room: usize,
    },
    /// An element line that is not `id type ntags tags... nodes`.
    #[error("element line: id type ntags tags... nodes")]
    ElementLine,
    /// Fewer numbers than the tags claimed.
    #[error("{tags} tags, but only {numbers} numbers follow")]
    Tags {
        /// The tags claimed.
        tags: usize,
        /// The numbers after them.
        numbers: usize,
    },
    /// An element of a type et does not mesh with (a quadrangle, a second-order or a 3-D
    /// element), which was dropped, leaving a hole where it was.
    #[error(
        "an element of Gmsh type {kind}, {}: et reads 3-node triangles (type 2), lines (1) \
         and points (15)",
        unread_element(*kind)
    )]
    ElementKind {
        /// Its Gmsh type.
        kind: i64,
    },
    /// An element with the wrong number of nodes for its type.
    #[error("an element of type {kind} has {want} nodes, this line gives {got}")]
    ElementNodes {
        /// Its Gmsh type.
        kind: i64,
        /// The nodes of that type.
        want: usize,
        /// The nodes given.
        got: usize,
    },
    /// A node id not in `$Nodes`.
    #[error("node {0} is not in $Nodes")]
    UnknownNode(i64),
    /// A line element with no physical tag.
    #[error("a line element without a physical tag")]
    Untagged,
}

/// Why a mesh file could not be read (the I/O error, shared so that [`MeshError`] stays
/// `Clone`; two are equal when their kind and text are).
#[derive(Debug, Clone, thiserror::Error)]
#[error("{0}")]
pub struct ReadError(pub(super) std::sync::Arc<std::io::Error>);

impl PartialEq for ReadError {
    fn eq(&self, other: &Self) -> bool {
        self.0.kind() == other.0.kind() && self.0.to_string() == other.0.to_string()
    }
}

/// What a Gmsh 2.2 element type et does not read is, and how to write the mesh instead.
fn unread_element(kind: i64) -> &'static str {
    match kind {
        3 | 10 | 16 => "a quadrangle: mesh with triangles (leave out Recombine)",
        8 | 9 | 20..=28 => {
            "a second- or higher-order element: save first-order elements (gmsh -order 1)"
        }
        4..=7 | 11..=14 | 17..=19 | 29.. => "a 3-D element: mesh the sheet in 2-D (gmsh -2)",
        _ => "a type Gmsh 2.2 does not define",
    }
}
