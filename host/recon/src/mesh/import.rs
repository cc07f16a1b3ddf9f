//! Meshes users bring: Gmsh ASCII `.msh` (format 2.2) and plain CSV.
//!
//! Gmsh: triangles are the 3-node triangle elements (type 2); electrodes are the 2-node line
//! elements (type 1), grouped by physical tag: the distinct tags in ascending order are
//! electrodes 0, 1, ... (give each electrode its own physical curve). A physical point (a
//! 1-node element, type 15) is a point electrode at that node. Coordinates are taken as
//! metres. Gmsh 4 files are refused with the hint to save as 2.2 (`gmsh -format msh22`).
//!
//! CSV: `nodes.csv` (x,y per row, m), `triangles.csv` (three 0-based node indices per row),
//! `electrodes.csv` (one row per electrode: its boundary node indices in order along it; a
//! single index is a point electrode at that node). A header row is allowed in each (a first
//! row that is not numeric is skipped), as are blank lines and `#` comments; errors name the
//! file's own line.
//!
//! A point electrode has no edges (`Mesh::electrodes` is empty for it) and its node as its
//! centre node: only the point model images with it.

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::{Mesh, MeshError};

mod checks;
mod fault;
use checks::{
    centre_node, check_connected, check_topology, check_unshared, orient, point_electrodes,
};
pub use fault::{FileFault, MESH_FILES, ReadError};

fn bad(path: &Path, line: usize, fault: FileFault) -> MeshError {
    MeshError::File {
        path: path.into(),
        line,
        fault,
    }
}

fn read(path: &Path) -> Result<String, MeshError> {
    et_core::text::read_text_at_most(path, et_core::text::max_file_bytes()).map_err(|e| {
        MeshError::Read {
            path: path.into(),
            source: ReadError(std::sync::Arc::new(e)),
        }
    })
}

/// Rows of comma-separated values with their line numbers (1-based), each `width` long if
/// given; blank lines and `#` comments are skipped, and a non-numeric first row is a header.
fn csv_rows<T: std::str::FromStr>(
    path: &Path,
    width: Option<(usize, &'static str)>,
) -> Result<Vec<(usize, Vec<T>)>, MeshError> {
    let text = read(path)?;
    let mut out = Vec::new();
    let mut first = true;
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let v: Result<Vec<T>, _> = line.split(',').map(|x| x.trim().parse::<T>()).collect();
        match v {
            Ok(v) if width.is_none_or(|(w, _)| v.len() == w) => out.push((i + 1, v)),
            Err(_) if first => {}
            _ => {
                let cells: Vec<&str> = line.split(',').map(str::trim).collect();
                let fault = match width {
                    Some((_, what)) => FileFault::Numbers {
                        found: cells.len(),
                        what,
                    },
                    None => {
                        let cell = cells.iter().find(|c| c.parse::<T>().is_err());
                        FileFault::NumberList(
                            cell.map_or(String::new(), |c| c.chars().take(40).collect()),
                        )
                    }
                };
                return Err(bad(path, i + 1, fault));
            }
        }
        first = false;
    }
    Ok(out)
}

impl Mesh {
    /// Reads a Gmsh 2.2 ASCII mesh (see the module docs).
    ///
    /// # Errors
    /// [`MeshError::Read`] or [`MeshError::File`] naming the file (and line), or what
    /// [`Mesh::from_parts`] finds.
    pub fn from_gmsh(path: &Path) -> Result<Self, MeshError> {
        // A file that is not text (an .npz of pyEIT's arrays, a .mat of EIDORS') is said with
        // what a mesh file is.
        let limit = et_core::text::max_file_bytes();
        let text = et_core::text::read_document_at_most(path, limit).map_err(|e| {
            if e.kind() == std::io::ErrorKind::InvalidData {
                let said = e.to_string();
                MeshError::NotMesh {
                    path: path.into(),
                    said,
                }
            } else {
                MeshError::Read {
                    path: path.into(),
                    source: ReadError(std::sync::Arc::new(e)),
                }
            }
        })?;
        let lines: Vec<&str> = text.lines().collect();
        let find = |tag: &str| lines.iter().position(|l| l.trim() == tag);
        let Some(fmt) = find("$MeshFormat") else {
            // Another of et's files (a recording, a protocol file) said as what it is.
            return Err(match et_core::text::EtFile::of(&text) {
                Some(kind) => MeshError::NotMesh {
                    path: path.into(),
                    said: format!("{}, not a mesh", kind.said()),
                },
                None => bad(path, 1, FileFault::NotGmsh),
            });
        };
        let head: Vec<&str> = lines
            .get(fmt + 1)
            .map(|l| l.split_whitespace().collect())
            .unwrap_or_default();
        let version = head.first().copied().unwrap_or("");
        if !version.starts_with("2.") {
            let version = version.to_string();
            return Err(bad(path, fmt + 2, FileFault::GmshVersion { version }));
        }
        if head.get(1) != Some(&"0") {
            return Err(bad(path, fmt + 2, FileFault::Binary));
        }
        let count = |i: usize, what: &'static str| gmsh_count(path, &lines, i, what);
        let nodes_at =
            find("$Nodes").ok_or_else(|| bad(path, 0, FileFault::NoSection("$Nodes")))?;
        let n = count(nodes_at + 1, "nodes")?;
        let mut ids = HashMap::new();
        let mut nodes = Vec::with_capacity(n);
        for i in 0..n {
            let ln = nodes_at + 2 + i;
            let v: Result<Vec<f64>, _> = lines.get(ln).map_or(Ok(Vec::new()), |l| {
                l.split_whitespace().map(str::parse).collect()
            });
            match v.as_deref() {
                Ok(&[id, x, y, ..]) if x.is_finite() && y.is_finite() => {
                    ids.insert(id as i64, nodes.len());
                    nodes.push([x, y]);
                }
                _ => return Err(bad(path, ln + 1, FileFault::NodeLine)),
            }
        }
        let el_at =
            find("$Elements").ok_or_else(|| bad(path, 0, FileFault::NoSection("$Elements")))?;
        let m = count(el_at + 1, "elements")?;
        let (triangles, by_tag) = gmsh_elements(path, &lines, (el_at + 2, m), &ids)?;
        Self::from_parts(nodes, triangles, by_tag.into_values().collect())
    }

    /// Reads a mesh from three CSV files (see the module docs).
    ///
    /// # Errors
    /// [`MeshError::Read`] or [`MeshError::File`] naming the file (and line), or what
    /// [`Mesh::from_parts`] finds.
    pub fn from_csv(nodes: &Path, triangles: &Path, electrodes: &Path) -> Result<Self, MeshError> {
        let xy: Vec<(usize, Vec<f64>)> = csv_rows(nodes, Some((2, "a node's x, y (m)")))?;
        if let Some((line, _)) = xy.iter().find(|(_, r)| r.iter().any(|v| !v.is_finite())) {
            return Err(bad(nodes, *line, FileFault::NonFinite));
        }
        let tri: Vec<(usize, Vec<usize>)> =
            csv_rows(triangles, Some((3, "a triangle's three node numbers")))?;
        let el: Vec<(usize, Vec<usize>)> = csv_rows(electrodes, None)?;
        // Node numbers past the nodes, named by file and line (from 0, as in the docs).
        let n = xy.len();
        for (path, rows) in [(triangles, &tri), (electrodes, &el)] {
            if let Some((line, v)) = rows
                .iter()
                .find_map(|(line, r)| r.iter().find(|&&v| v >= n).map(|v| (line, v)))
            {
                let fault = FileFault::NodePast {
                    node: *v,
                    nodes: nodes.into(),
                    count: n,
                };
                return Err(bad(path, *line, fault));
            }
        }
        // csv_rows gave each row its width; a row that is not is refused, not indexed.
        let width = |path: &Path, line: usize| bad(path, line, FileFault::Width);
        let xy = xy
            .iter()
            .map(|(line, r)| match r[..] {
                [x, y] => Ok([x, y]),
                _ => Err(width(nodes, *line)),
            })
            .collect::<Result<_, _>>()?;
        let tri = tri
            .iter()
            .map(|(line, r)| match r[..] {
                [a, b, c] => Ok([a, b, c]),
                _ => Err(width(triangles, *line)),
            })
            .collect::<Result<_, _>>()?;
        let el = el
            .iter()
            .map(|(_, r)| match r[..] {
                [a] => vec![[a, a]], // a point electrode
                _ => r
                    .windows(2)
                    .filter_map(|w| match *w {
                        [a, b] => Some([a, b]),
                        _ => None,
                    })
                    .collect(),
            })
            .collect();
        Self::from_parts(xy, tri, el)
    }

    /// A mesh from its parts, checked: indices in range, triangles turned counter-clockwise,
    /// degenerate triangles (area below 1e-12 of the mean) refused, every electrode with an
    /// edge or a single node (written as the edge `[i, i]`: a point electrode, stored with no
    /// edges) on the boundary; an electrode's centre node is its node nearest the mean of its
    /// nodes.
    ///
    /// # Errors
    /// The [`MeshError`] naming the first fault: a node number past the nodes
    /// ([`MeshError::TriangleNodePast`]), a degenerate or repeated triangle, an unused node, an
    /// electrode that is empty, mixed, shared or not on the boundary.
    pub fn from_parts(
        nodes: Vec<[f64; 2]>,
        mut triangles: Vec<[usize; 3]>,
        electrodes: Vec<Vec<[usize; 2]>>,
    ) -> Result<Self, MeshError> {
        let n = nodes.len();
        if triangles.is_empty() {
            return Err(MeshError::NoTriangles);
        }
        if electrodes.len() < 2 {
            return Err(MeshError::TooFewElectrodes {
                count: electrodes.len(),
            });
        }
        if let Some(t) = triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
            return Err(MeshError::TriangleNodePast {
                triangle: t,
                nodes: n,
            });
        }
        if electrodes.iter().flatten().flatten().any(|&i| i >= n) {
            return Err(MeshError::ElectrodeNodePast { nodes: n });
        }
        orient(&nodes, &mut triangles)?;
        if let Some(l) = electrodes.iter().position(Vec::is_empty) {
            return Err(MeshError::EmptyElectrode { electrode: l });
        }
        let point = point_electrodes(&electrodes)?;
        let mut electrodes = electrodes;
        for (el, p) in electrodes.iter_mut().zip(&point) {
            if p.is_some() {
                el.clear();
            }
        }
        check_topology(&nodes, &triangles, &electrodes, &point)?;
        check_connected(n, &triangles, &electrodes, &point)?;
        check_unshared(n, &electrodes, &point)?;
        let centre_nodes = electrodes
            .iter()
            .zip(&point)
            .map(|(edges, p)| p.unwrap_or_else(|| centre_node(&nodes, edges)))
            .collect();
        Ok(Self {
            nodes,
            triangles,
            electrodes,
            centre_nodes,
        })
    }
}

/// The number on line index `i` of a Gmsh file's `lines`, believed only as far as the file
/// holds lines for it (nothing is allocated for a count the file cannot back); `what` names
/// what is counted in the error.
fn gmsh_count(
    path: &Path,
    lines: &[&str],
    i: usize,
    what: &'static str,
) -> Result<usize, MeshError> {
    let n: usize = lines
        .get(i)
        .and_then(|l| l.trim().parse().ok())
        .ok_or_else(|| bad(path, i + 1, FileFault::Count))?;
    let room = lines.len().saturating_sub(i + 1);
    if n > room {
        let fault = FileFault::CountPastEnd {
            count: n,
            what,
            room,
        };
        return Err(bad(path, i + 1, fault));
    }
    Ok(n)
}

/// A Gmsh file's `m` elements from line index `first` of its `lines` (`ids`: each node id's
/// index): its triangles, and its line and point elements by physical tag (the electrodes;
/// a point as the edge [a, a]).
#[allow(clippy::type_complexity)]
fn gmsh_elements(
    path: &Path,
    lines: &[&str],
    (first, m): (usize, usize),
    ids: &HashMap<i64, usize>,
) -> Result<(Vec<[usize; 3]>, BTreeMap<i64, Vec<[usize; 2]>>), MeshError> {
    let mut triangles = Vec::new();
    let mut by_tag: BTreeMap<i64, Vec<[usize; 2]>> = BTreeMap::new();
    for i in 0..m {
        let ln = first + i;
        let v: Result<Vec<i64>, _> = lines.get(ln).map_or(Ok(Vec::new()), |l| {
            l.split_whitespace().map(str::parse).collect()
        });
        let (kind, ntags, rest) = match v.as_deref() {
            Ok(&[_, kind, ntags, ref rest @ ..]) => {
                (kind, usize::try_from(ntags).unwrap_or(usize::MAX), rest)
            }
            _ => {
                return Err(bad(path, ln + 1, FileFault::ElementLine));
            }
        };
        let (Some(tags), Some(conn)) = (rest.get(..ntags), rest.get(ntags..)) else {
            let fault = FileFault::Tags {
                tags: ntags,
                numbers: rest.len(),
            };
            return Err(bad(path, ln + 1, fault));
        };
        let nodes_of = |kind: i64| match kind {
            1 => Some(2),
            2 => Some(3),
            15 => Some(1),
            _ => None,
        };
        if let Some(want) = nodes_of(kind)
            && conn.len() != want
        {
            let fault = FileFault::ElementNodes {
                kind,
                want,
                got: conn.len(),
            };
            return Err(bad(path, ln + 1, fault));
        }
        let node = |id: i64| {
            ids.get(&id)
                .copied()
                .ok_or_else(|| bad(path, ln + 1, FileFault::UnknownNode(id)))
        };
        match (kind, conn) {
            (2, &[a, b, c]) => triangles.push([node(a)?, node(b)?, node(c)?]),
            (1, &[a, b]) => {
                let tag = *tags
                    .first()
                    .ok_or_else(|| bad(path, ln + 1, FileFault::Untagged))?;
                by_tag.entry(tag).or_default().push([node(a)?, node(b)?]);
            }
            (15, &[a]) => {
                // A physical point: a point electrode (written as the edge [a, a]).
                if let Some(&tag) = tags.first() {
                    let a = node(a)?;
                    by_tag.entry(tag).or_default().push([a, a]);
                }
            }
            // (Types 1, 2 and 15 of other node counts were refused above.)
            (kind, _) => return Err(bad(path, ln + 1, FileFault::ElementKind { kind })),
        }
    }
    Ok((triangles, by_tag))
}
