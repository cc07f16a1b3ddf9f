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
//! row that is not numeric is skipped).
//!
//! A point electrode has no edges (`Mesh::electrodes` is empty for it) and its node as its
//! centre node: only the point model images with it.

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::{Mesh, MeshError, dist};

fn bad(path: &Path, line: usize, why: impl std::fmt::Display) -> MeshError {
    MeshError::Spec(format!("{}:{line}: {why}", path.display()))
}

fn read(path: &Path) -> Result<String, MeshError> {
    std::fs::read_to_string(path).map_err(|e| MeshError::Spec(format!("{}: {e}", path.display())))
}

/// Rows of comma-separated values, each `width` long if given; a non-numeric first row is a
/// header.
fn csv_rows<T: std::str::FromStr>(
    path: &Path,
    width: Option<usize>,
) -> Result<Vec<Vec<T>>, MeshError> {
    let text = read(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let v: Result<Vec<T>, _> = line.split(',').map(|x| x.trim().parse::<T>()).collect();
        match v {
            Ok(v) if width.is_none_or(|w| v.len() == w) => out.push(v),
            Err(_) if i == 0 => {}
            _ => {
                let what = width.map_or("a list of".to_string(), |w| w.to_string());
                return Err(bad(path, i + 1, format!("expected {what} numbers")));
            }
        }
    }
    Ok(out)
}

impl Mesh {
    /// Reads a Gmsh 2.2 ASCII mesh (see the module docs).
    ///
    /// # Errors
    /// [`MeshError::Spec`] naming the file and line, or what [`Mesh::from_parts`] finds.
    pub fn from_gmsh(path: &Path) -> Result<Self, MeshError> {
        let text = read(path)?;
        let lines: Vec<&str> = text.lines().collect();
        let find = |tag: &str| lines.iter().position(|l| l.trim() == tag);
        let fmt =
            find("$MeshFormat").ok_or_else(|| bad(path, 1, "no $MeshFormat: not a Gmsh file"))?;
        let head: Vec<&str> = lines
            .get(fmt + 1)
            .map(|l| l.split_whitespace().collect())
            .unwrap_or_default();
        let version = head.first().copied().unwrap_or("");
        if !version.starts_with("2.") {
            return Err(bad(
                path,
                fmt + 2,
                format!(
                    "Gmsh format {version}: only 2.2 ASCII is read; save with `gmsh -format msh22`"
                ),
            ));
        }
        if head.get(1) != Some(&"0") {
            return Err(bad(path, fmt + 2, "binary Gmsh file: save as ASCII"));
        }
        // The count on line index `i`, believed only as far as the file holds lines for it
        // (nothing is allocated for a count the file cannot back).
        let count = |i: usize, what: &str| -> Result<usize, MeshError> {
            let n: usize = lines
                .get(i)
                .and_then(|l| l.trim().parse().ok())
                .ok_or_else(|| bad(path, i + 1, "expected a count"))?;
            let room = lines.len().saturating_sub(i + 1);
            if n > room {
                return Err(bad(
                    path,
                    i + 1,
                    format!("{n} {what} claimed; the file has {room} lines after the count"),
                ));
            }
            Ok(n)
        };
        let nodes_at = find("$Nodes").ok_or_else(|| bad(path, 0, "no $Nodes section"))?;
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
                _ => return Err(bad(path, ln + 1, "node line: id x y z")),
            }
        }
        let el_at = find("$Elements").ok_or_else(|| bad(path, 0, "no $Elements section"))?;
        let m = count(el_at + 1, "elements")?;
        let mut triangles = Vec::new();
        let mut by_tag: BTreeMap<i64, Vec<[usize; 2]>> = BTreeMap::new();
        for i in 0..m {
            let ln = el_at + 2 + i;
            let v: Result<Vec<i64>, _> = lines.get(ln).map_or(Ok(Vec::new()), |l| {
                l.split_whitespace().map(str::parse).collect()
            });
            let (kind, ntags, rest) = match v.as_deref() {
                Ok(&[_, kind, ntags, ref rest @ ..]) => {
                    (kind, usize::try_from(ntags).unwrap_or(0), rest)
                }
                _ => {
                    return Err(bad(
                        path,
                        ln + 1,
                        "element line: id type ntags tags... nodes",
                    ));
                }
            };
            let tags = rest.get(..ntags).unwrap_or(&[]);
            let conn = rest.get(ntags..).unwrap_or(&[]);
            let node = |id: i64| {
                ids.get(&id)
                    .copied()
                    .ok_or_else(|| bad(path, ln + 1, format!("node {id} is not in $Nodes")))
            };
            match (kind, conn) {
                (2, &[a, b, c]) => triangles.push([node(a)?, node(b)?, node(c)?]),
                (1, &[a, b]) => {
                    let tag = *tags.first().ok_or_else(|| {
                        bad(path, ln + 1, "a line element without a physical tag")
                    })?;
                    by_tag.entry(tag).or_default().push([node(a)?, node(b)?]);
                }
                (15, &[a]) => {
                    // A physical point: a point electrode (written as the edge [a, a]).
                    if let Some(&tag) = tags.first() {
                        let a = node(a)?;
                        by_tag.entry(tag).or_default().push([a, a]);
                    }
                }
                _ => {} // points, quadrangles and higher orders are not used
            }
        }
        Self::from_parts(nodes, triangles, by_tag.into_values().collect())
    }

    /// Reads a mesh from three CSV files (see the module docs).
    ///
    /// # Errors
    /// [`MeshError::Spec`] naming the file and line, or what [`Mesh::from_parts`] finds.
    pub fn from_csv(nodes: &Path, triangles: &Path, electrodes: &Path) -> Result<Self, MeshError> {
        let xy: Vec<Vec<f64>> = csv_rows(nodes, Some(2))?;
        if let Some(i) = xy.iter().position(|r| r.iter().any(|v| !v.is_finite())) {
            return Err(bad(nodes, i + 1, "non-finite coordinate"));
        }
        let tri: Vec<Vec<usize>> = csv_rows(triangles, Some(3))?;
        let el: Vec<Vec<usize>> = csv_rows(electrodes, None)?;
        // csv_rows gave each row its width; a row that is not is refused, not indexed.
        let width = |path: &Path, i: usize| bad(path, i + 1, "wrong number of values");
        let xy = xy
            .iter()
            .enumerate()
            .map(|(i, r)| match r[..] {
                [x, y] => Ok([x, y]),
                _ => Err(width(nodes, i)),
            })
            .collect::<Result<_, _>>()?;
        let tri = tri
            .iter()
            .enumerate()
            .map(|(i, r)| match r[..] {
                [a, b, c] => Ok([a, b, c]),
                _ => Err(width(triangles, i)),
            })
            .collect::<Result<_, _>>()?;
        let el = el
            .iter()
            .map(|r| match r[..] {
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
    /// [`MeshError::Spec`] or [`MeshError::EmptyElectrode`].
    pub fn from_parts(
        nodes: Vec<[f64; 2]>,
        mut triangles: Vec<[usize; 3]>,
        electrodes: Vec<Vec<[usize; 2]>>,
    ) -> Result<Self, MeshError> {
        let n = nodes.len();
        if triangles.is_empty() {
            return Err(MeshError::Spec("no triangles".into()));
        }
        if electrodes.len() < 2 {
            return Err(MeshError::Spec(format!(
                "{} electrodes: need at least 2",
                electrodes.len()
            )));
        }
        if let Some(t) = triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
            return Err(MeshError::Spec(format!(
                "triangle {t} names a node past the {n} nodes"
            )));
        }
        if electrodes.iter().flatten().flatten().any(|&i| i >= n) {
            return Err(MeshError::Spec(format!(
                "an electrode names a node past the {n} nodes"
            )));
        }
        // Indices are in range (checked above); NaN otherwise, which is refused as degenerate.
        let at = |i: usize| nodes.get(i).copied().unwrap_or([f64::NAN; 2]);
        let area2 = |t: &[usize; 3]| {
            let [a, b, c] = t.map(at);
            (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
        };
        let mean = triangles.iter().map(|t| area2(t).abs()).sum::<f64>() / triangles.len() as f64;
        for (i, t) in triangles.iter_mut().enumerate() {
            let a = area2(t);
            if a.is_nan() || a.abs() <= 1e-12 * mean {
                return Err(MeshError::Spec(format!(
                    "triangle {i} is degenerate (area {:.3e} m^2)",
                    0.5 * a.abs()
                )));
            }
            if a < 0.0 {
                t.swap(1, 2);
            }
        }
        if let Some(l) = electrodes.iter().position(Vec::is_empty) {
            return Err(MeshError::EmptyElectrode { electrode: l });
        }
        // Point electrodes: only [i, i] entries, all the same node.
        let point: Vec<Option<usize>> = electrodes
            .iter()
            .map(|el| {
                let first = el.first()?[0];
                el.iter()
                    .all(|&[a, b]| a == first && b == first)
                    .then_some(first)
            })
            .collect();
        if let Some(l) = (0..electrodes.len()).find(|&l| {
            point.get(l).copied().flatten().is_none()
                && electrodes
                    .get(l)
                    .is_some_and(|el| el.iter().any(|&[a, b]| a == b))
        }) {
            return Err(MeshError::Spec(format!(
                "electrode {l} mixes a single node with edges: give one node (a point \
                 electrode) or its nodes in order along the boundary"
            )));
        }
        let mut electrodes = electrodes;
        for (el, p) in electrodes.iter_mut().zip(&point) {
            if p.is_some() {
                el.clear();
            }
        }
        check_topology(n, &triangles, &electrodes, &point)?;
        let centre_nodes = electrodes
            .iter()
            .zip(&point)
            .map(|(edges, p)| {
                if let Some(i) = *p {
                    return i;
                }
                let mut v: Vec<usize> = edges.iter().flatten().copied().collect();
                v.sort_unstable();
                v.dedup();
                let k = v.len() as f64;
                let c = v.iter().fold([0.0, 0.0], |[sx, sy], &i| {
                    let [x, y] = at(i);
                    [sx + x / k, sy + y / k]
                });
                v.iter()
                    .copied()
                    .min_by(|&a, &b| dist(at(a), c).total_cmp(&dist(at(b), c)))
                    .unwrap_or(0)
            })
            .collect();
        Ok(Self {
            nodes,
            triangles,
            electrodes,
            centre_nodes,
        })
    }
}

/// What the finite elements need of a mesh's topology, each with its cause named: every
/// triangle once (a repeated one doubles its conductance), every node in a triangle (an unused
/// node makes the system singular), and every electrode edge an edge of exactly one triangle,
/// the boundary (an edge inside the mesh, or nodes out of order along an electrode, changed
/// the voltages by up to 84 % without a word).
fn check_topology(
    n: usize,
    triangles: &[[usize; 3]],
    electrodes: &[Vec<[usize; 2]>],
    point: &[Option<usize>],
) -> Result<(), MeshError> {
    let mut seen: HashMap<[usize; 3], usize> = HashMap::with_capacity(triangles.len());
    let mut edges: HashMap<[usize; 2], u32> = HashMap::with_capacity(2 * triangles.len());
    let mut used = vec![false; n];
    let edge = |a: usize, b: usize| [a.min(b), a.max(b)];
    for (i, t) in triangles.iter().enumerate() {
        let mut key = *t;
        key.sort_unstable();
        if let Some(j) = seen.insert(key, i) {
            return Err(MeshError::Spec(format!(
                "triangle {i} repeats triangle {j}"
            )));
        }
        let [a, b, c] = *t;
        for v in [a, b, c] {
            if let Some(u) = used.get_mut(v) {
                *u = true;
            }
        }
        for e in [edge(a, b), edge(b, c), edge(c, a)] {
            *edges.entry(e).or_default() += 1;
        }
    }
    if let Some(v) = used.iter().position(|&u| !u) {
        return Err(MeshError::Spec(format!(
            "node {v} is in no triangle (an unused node leaves the system singular)"
        )));
    }
    let mut boundary = vec![false; n];
    for (e, &count) in &edges {
        if count == 1 {
            for &v in e {
                if let Some(b) = boundary.get_mut(v) {
                    *b = true;
                }
            }
        }
    }
    let on_boundary = |v: usize| boundary.get(v).copied().unwrap_or(false);
    for (l, p) in point.iter().enumerate() {
        if let Some(v) = *p
            && !on_boundary(v)
        {
            return Err(MeshError::Spec(format!(
                "electrode {l}: node {v} is inside the mesh, not on its boundary"
            )));
        }
    }
    for (l, el) in electrodes.iter().enumerate() {
        for &[a, b] in el {
            match edges.get(&edge(a, b)) {
                Some(1) => {}
                Some(_) => {
                    return Err(MeshError::Spec(format!(
                        "electrode {l}: edge ({a}, {b}) is inside the mesh, not on its boundary"
                    )));
                }
                None => {
                    return Err(MeshError::Spec(format!(
                        "electrode {l}: nodes {a} and {b} share no triangle edge (list an \
                         electrode's nodes in order along the boundary)"
                    )));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use crate::fem::{Electrodes, Forward};
    use crate::mesh::MeshSize;
    use et_core::protocol::{Protocol, ProtocolKind};
    use et_core::sheet::Sheet;

    fn tmp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("et-mesh-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// `mesh` as Gmsh 2.2 (1-based ids, electrodes as physical lines 101, 102, ...,
    /// triangles written clockwise for the reader to turn).
    fn to_gmsh(mesh: &Mesh) -> String {
        use std::fmt::Write as _;
        let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
        let _ = writeln!(s, "{}", mesh.nodes.len());
        for (i, p) in mesh.nodes.iter().enumerate() {
            let _ = writeln!(s, "{} {} {} 0", i + 1, p[0], p[1]);
        }
        let lines: Vec<(usize, [usize; 2])> = mesh
            .electrodes
            .iter()
            .enumerate()
            .flat_map(|(l, e)| e.iter().map(move |&x| (l, x)))
            .collect();
        let _ = writeln!(
            s,
            "$EndNodes\n$Elements\n{}",
            lines.len() + mesh.triangles.len()
        );
        let mut id = 1;
        for (l, [a, b]) in &lines {
            let _ = writeln!(s, "{id} 1 2 {} 1 {} {}", 101 + l, a + 1, b + 1);
            id += 1;
        }
        for t in &mesh.triangles {
            let _ = writeln!(s, "{id} 2 2 1 1 {} {} {}", t[0] + 1, t[2] + 1, t[1] + 1);
            id += 1;
        }
        s.push_str("$EndElements\n");
        s
    }

    /// An electrode's nodes in order along it.
    fn chain(edges: &[[usize; 2]]) -> Vec<usize> {
        let mut c = vec![edges[0][0], edges[0][1]];
        let mut left: Vec<[usize; 2]> = edges[1..].to_vec();
        while let Some(i) = left
            .iter()
            .position(|e| e.contains(c.last().unwrap()) || e.contains(&c[0]))
        {
            let e = left.remove(i);
            let last = *c.last().unwrap();
            match () {
                () if e[0] == last => c.push(e[1]),
                () if e[1] == last => c.push(e[0]),
                () if e[0] == c[0] => c.insert(0, e[1]),
                () => c.insert(0, e[0]),
            }
        }
        c
    }

    #[test]
    fn gmsh_and_csv_meshes_give_the_same_voltages_as_the_original() {
        let spec = Sheet::rectangle(0.13, 0.13, 8);
        let mesh = Mesh::of_sheet(&spec, MeshSize::for_count(&spec, 800)).unwrap();
        let dir = tmp("rt");
        let msh = dir.join("m.msh");
        std::fs::write(&msh, to_gmsh(&mesh)).unwrap();
        let g = Mesh::from_gmsh(&msh).unwrap();
        let write = |name: &str, rows: Vec<String>| {
            let p = dir.join(name);
            std::fs::write(&p, rows.join("\n")).unwrap();
            p
        };
        let nodes = write(
            "nodes.csv",
            std::iter::once("x,y".to_string())
                .chain(mesh.nodes.iter().map(|p| format!("{},{}", p[0], p[1])))
                .collect(),
        );
        let tris = write(
            "triangles.csv",
            mesh.triangles
                .iter()
                .map(|t| format!("{},{},{}", t[0], t[1], t[2]))
                .collect(),
        );
        let els = write(
            "electrodes.csv",
            mesh.electrodes
                .iter()
                .map(|e| {
                    chain(e)
                        .iter()
                        .map(usize::to_string)
                        .collect::<Vec<_>>()
                        .join(",")
                })
                .collect(),
        );
        let c = Mesh::from_csv(&nodes, &tris, &els).unwrap();
        let protocol = Protocol::new(ProtocolKind::Adjacent, 8).unwrap();
        let frame = |m: Mesh| {
            let n = m.triangles.len();
            Forward::new(m, Electrodes::Complete(vec![5.0; 8]))
                .unwrap()
                .frame(&vec![1e-4; n], &protocol, 1e-4)
                .unwrap()
        };
        let (v, vg, vc) = (frame(mesh), frame(g), frame(c));
        for k in 0..v.len() {
            let tol = 1e-9 * v[k].abs().max(1e-3);
            assert!(
                (v[k] - vg[k]).abs() < tol,
                "gmsh row {k}: {} vs {}",
                v[k],
                vg[k]
            );
            assert!(
                (v[k] - vc[k]).abs() < tol,
                "csv row {k}: {} vs {}",
                v[k],
                vc[k]
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// One-node electrodes (a CSV row of one index, a Gmsh physical point) are point
    /// electrodes: the same voltages as the point model on the original mesh; the complete
    /// model refuses them by name; a node inside the mesh, or a node mixed with edges, is
    /// refused.
    #[test]
    fn one_node_electrodes_are_point_electrodes() {
        let spec = Sheet::rectangle(0.13, 0.13, 8);
        let mesh = Mesh::of_sheet(&spec, MeshSize::for_count(&spec, 800)).unwrap();
        let dir = tmp("point");
        let write = |name: &str, text: String| {
            let p = dir.join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        let rows = |v: &mut dyn Iterator<Item = String>| v.collect::<Vec<_>>().join("\n");
        let nodes = write(
            "nodes.csv",
            rows(&mut mesh.nodes.iter().map(|p| format!("{},{}", p[0], p[1]))),
        );
        let tris = write(
            "triangles.csv",
            rows(
                &mut mesh
                    .triangles
                    .iter()
                    .map(|t| format!("{},{},{}", t[0], t[1], t[2])),
            ),
        );
        let els = write(
            "electrodes.csv",
            rows(&mut mesh.centre_nodes.iter().map(usize::to_string)),
        );
        let c = Mesh::from_csv(&nodes, &tris, &els).unwrap();
        assert!(c.electrodes.iter().all(Vec::is_empty));
        assert_eq!(c.centre_nodes, mesh.centre_nodes);
        // Gmsh: the same electrodes as physical points.
        let mut g = to_gmsh(&Mesh {
            electrodes: vec![Vec::new(); 8],
            ..mesh.clone()
        });
        let points: String = mesh
            .centre_nodes
            .iter()
            .enumerate()
            .map(|(l, &i)| format!("{} 15 2 {} 1 {}\n", 900_000 + l, 201 + l, i + 1))
            .collect();
        let count = mesh.triangles.len();
        g = g.replacen(
            &format!("$Elements\n{count}\n"),
            &format!("$Elements\n{}\n{points}", count + 8),
            1,
        );
        let g = Mesh::from_gmsh(&write("p.msh", g)).unwrap();
        assert_eq!(g.centre_nodes, mesh.centre_nodes);
        let protocol = Protocol::new(ProtocolKind::Adjacent, 8).unwrap();
        let frame = |m: Mesh| {
            let n = m.triangles.len();
            Forward::new(m, Electrodes::Point)
                .unwrap()
                .frame(&vec![1e-4; n], &protocol, 1e-4)
                .unwrap()
        };
        let v = frame(mesh.clone());
        for other in [frame(c.clone()), frame(g)] {
            for (a, b) in v.iter().zip(&other) {
                assert!((a - b).abs() < 1e-9 * a.abs().max(1e-3), "{a} vs {b}");
            }
        }
        let e = Forward::new(c, Electrodes::Complete(vec![5.0; 8])).unwrap_err();
        assert!(e.to_string().contains("point"), "{e}");
        // A node inside the mesh (not on the boundary), and a node mixed with edges.
        let inner = (0..mesh.nodes.len())
            .find(|&i| spec.shape.distance_to_outline(mesh.nodes[i]) > 0.01)
            .unwrap();
        let mut bad: Vec<String> = mesh.centre_nodes.iter().map(usize::to_string).collect();
        bad[3] = inner.to_string();
        let e = Mesh::from_csv(&nodes, &tris, &write("bad.csv", bad.join("\n"))).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("electrode 3: node {inner} is inside")),
            "{e}"
        );
        let mut electrodes: Vec<Vec<[usize; 2]>> =
            mesh.centre_nodes.iter().map(|&i| vec![[i, i]]).collect();
        electrodes[2].push(mesh.electrodes[2][0]);
        let e =
            Mesh::from_parts(mesh.nodes.clone(), mesh.triangles.clone(), electrodes).unwrap_err();
        assert!(e.to_string().contains("electrode 2 mixes"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_files_name_the_file_and_line_and_slivers_stay_finite() {
        let dir = tmp("bad");
        let p = dir.join("v4.msh");
        std::fs::write(&p, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n").unwrap();
        let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
        assert!(e.contains("v4.msh:2") && e.contains("msh22"), "{e}");
        let p = dir.join("n.msh");
        std::fs::write(
            &p,
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 x 1 0\n$EndNodes\n",
        )
        .unwrap();
        let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
        assert!(e.contains("n.msh:7"), "{e}");
        // Counts beyond what the file holds are refused before anything is allocated (10^18
        // nodes was a capacity-overflow panic, 10^10 an allocation abort).
        for (section, count) in [("Nodes", "1000000000000000000"), ("Nodes", "10000000000")] {
            let p = dir.join("huge.msh");
            std::fs::write(
                &p,
                format!("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n${section}\n{count}\n1 0 0 0\n"),
            )
            .unwrap();
            let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
            assert!(e.contains("huge.msh:5") && e.contains(count), "{e}");
        }
        let p = dir.join("huge-el.msh");
        std::fs::write(
            &p,
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n99999999999\n1 2 3 1 1 1 1\n",
        )
        .unwrap();
        let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
        assert!(e.contains("99999999999 elements"), "{e}");
        let p = dir.join("t.csv");
        std::fs::write(&p, "a,b,c\n0,1,2\n0,1\n").unwrap();
        let e = Mesh::from_csv(&p, &p, &p).unwrap_err().to_string();
        assert!(e.contains("t.csv:2"), "{e}");
        // A sliver of zero area is refused; one of tiny area keeps finite potentials.
        let nodes = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.0]];
        let tris = vec![[0, 4, 1], [0, 1, 2], [0, 2, 3]];
        let flat = Mesh::from_parts(
            nodes.clone(),
            tris.clone(),
            vec![vec![[0, 4]], vec![[2, 3]]],
        );
        assert!(matches!(flat, Err(MeshError::Spec(m)) if m.contains("degenerate")));
        let mut thin = nodes;
        thin[4] = [0.5, -1e-7];
        let m = Mesh::from_parts(thin, tris, vec![vec![[0, 4], [4, 1]], vec![[2, 3]]]).unwrap();
        let fwd = Forward::new(m, Electrodes::Complete(vec![1.0, 1.0])).unwrap();
        let c = nalgebra::DMatrix::from_column_slice(2, 1, &[1e-3, -1e-3]);
        let sol = fwd.solve(&[1.0, 1.0, 1.0], &c).unwrap();
        assert!(sol.nodes.iter().all(|v| v.is_finite()));
        let out_of_range = Mesh::from_parts(
            vec![[0.0, 0.0]; 3],
            vec![[0, 1, 5]],
            vec![vec![[0, 1]], vec![[1, 2]]],
        );
        assert!(matches!(out_of_range, Err(MeshError::Spec(_))));
        // Topology: each fault named (they were accepted and changed the voltages).
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let two = vec![[0, 1, 2], [0, 2, 3]];
        let good = vec![vec![[0, 1]], vec![[2, 3]]];
        Mesh::from_parts(square.clone(), two.clone(), good.clone()).unwrap();
        type Parts = (Vec<[f64; 2]>, Vec<[usize; 3]>, Vec<Vec<[usize; 2]>>);
        let cases: [(Parts, &str); 4] = [
            (
                (
                    square.clone(),
                    vec![[0, 1, 2], [0, 2, 3], [2, 0, 1]],
                    good.clone(),
                ),
                "triangle 2 repeats triangle 0",
            ),
            (
                (
                    [square.clone(), vec![[2.0, 2.0]]].concat(),
                    two.clone(),
                    good.clone(),
                ),
                "node 4 is in no triangle",
            ),
            (
                (
                    square.clone(),
                    two.clone(),
                    vec![vec![[0, 2]], vec![[2, 3]]],
                ),
                "edge (0, 2) is inside the mesh",
            ),
            (
                (square, two, vec![vec![[1, 3]], vec![[2, 3]]]),
                "nodes 1 and 3 share no triangle edge",
            ),
        ];
        for ((nodes, tris, electrodes), what) in cases {
            let e = Mesh::from_parts(nodes, tris, electrodes)
                .unwrap_err()
                .to_string();
            assert!(e.contains(what), "{what}: {e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
