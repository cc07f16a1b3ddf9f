//! What the finite elements need of an imported mesh, each fault named: triangles turned one
//! way and of some area, none over another, every piece reached by an electrode, electrodes
//! on the boundary and apart.

use std::collections::HashMap;

use super::super::{MeshError, dist};

/// Node `i` of `nodes` (m), or NaN past their end (which the checks refuse as degenerate).
fn node(nodes: &[[f64; 2]], i: usize) -> [f64; 2] {
    nodes.get(i).copied().unwrap_or([f64::NAN; 2])
}

/// Every triangle turned counter-clockwise; a degenerate one (area below 1e-12 of the mean, or
/// NaN) refused.
pub(super) fn orient(nodes: &[[f64; 2]], triangles: &mut [[usize; 3]]) -> Result<(), MeshError> {
    let area2 = |t: &[usize; 3]| {
        let [a, b, c] = t.map(|i| node(nodes, i));
        (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
    };
    let mean = triangles.iter().map(|t| area2(t).abs()).sum::<f64>() / triangles.len() as f64;
    for (i, t) in triangles.iter_mut().enumerate() {
        let a = area2(t);
        if a.is_nan() || a.abs() <= 1e-12 * mean {
            return Err(MeshError::Degenerate {
                triangle: i,
                area: 0.5 * a.abs(),
            });
        }
        if a < 0.0 {
            t.swap(1, 2);
        }
    }
    Ok(())
}

/// Triangles (counter-clockwise, [`orient`]) that overlap, refused by two of them and a node
/// they share: at every node, the corners of its triangles (each the angle from the
/// direction of its next node to that of its last) must not cover one another. The finite
/// elements would add the conductances where triangles overlap: a triangle laid over half a
/// 13 cm square sheet made |V_1 - V_0| nine times the mesh's without it, without a word.
/// Holes and notches (a sheet with a cut-out) are meshes.
pub(super) fn check_overlap(nodes: &[[f64; 2]], triangles: &[[usize; 3]]) -> Result<(), MeshError> {
    use std::f64::consts::TAU;
    // (node, start and end of the corner, radians, end > start; triangle)
    let mut corners: Vec<(usize, f64, f64, usize)> = Vec::with_capacity(3 * triangles.len());
    for (i, &[t0, t1, t2]) in triangles.iter().enumerate() {
        for [a, b, c] in [[t0, t1, t2], [t1, t2, t0], [t2, t0, t1]] {
            let [pa, pb, pc] = [a, b, c].map(|v| node(nodes, v));
            let start = (pb[1] - pa[1]).atan2(pb[0] - pa[0]);
            let end = (pc[1] - pa[1]).atan2(pc[0] - pa[0]);
            corners.push((a, start, if end < start { end + TAU } else { end }, i));
        }
    }
    corners.sort_unstable_by(|p, q| p.0.cmp(&q.0).then(p.1.total_cmp(&q.1)));
    // Corners that share a side meet at one direction, to rounding (1e-15 rad).
    let slack = 1e-9;
    let overlap =
        |p: &(usize, f64, f64, usize), q: &(usize, f64, f64, usize)| MeshError::Overlapping {
            triangles: [p.3.min(q.3), p.3.max(q.3)],
            node: p.0,
        };
    for around in corners.chunk_by(|p, q| p.0 == q.0) {
        for pair in around.windows(2) {
            if let [p, q] = pair
                && p.2 > q.1 + slack
            {
                return Err(overlap(p, q));
            }
        }
        // The last corner round to the first, a turn on.
        if let (Some(first), Some(last)) = (around.first(), around.last())
            && around.len() > 1
            && last.2 > first.1 + TAU + slack
        {
            return Err(overlap(last, first));
        }
    }
    Ok(())
}

/// The boundary's `edges` (node pairs) crossing or touching none but their neighbours: a
/// boundary that crosses itself where no node is shared is triangles laid over others without
/// a common corner (a sheet meshed folded over itself, or two pieces over each other), which
/// [`check_overlap`] cannot see. Edges are swept by their leftmost x, each tested against those
/// whose x range meets its own (orientation tests; an end on another edge counts). A slit
/// (a cut meshed with its nodes doubled, each side a boundary) is a sheet: nodes at one point
/// count as one, and edges along one line (a slit's two sides) do not cross.
pub(super) fn check_boundary_uncrossed(
    nodes: &[[f64; 2]],
    edges: &[[usize; 2]],
) -> Result<(), MeshError> {
    let side = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).signum()
    };
    // Each boundary node's point, by its bits: nodes at one point are one corner.
    let mut points: HashMap<[u64; 2], usize> = HashMap::new();
    let mut point_of: HashMap<usize, usize> = HashMap::new();
    for &v in edges.iter().flatten() {
        let at = node(nodes, v).map(|x| (x + 0.0).to_bits());
        let next = points.len();
        point_of.insert(v, *points.entry(at).or_insert(next));
    }
    let point = |v: usize| point_of.get(&v).copied().unwrap_or(usize::MAX);
    // (x min, x max, y min, y max, edge)
    let mut spans: Vec<(f64, f64, f64, f64, [usize; 2])> = (edges.iter())
        .map(|&[a, b]| {
            let (p, q) = (node(nodes, a), node(nodes, b));
            (
                p[0].min(q[0]),
                p[0].max(q[0]),
                p[1].min(q[1]),
                p[1].max(q[1]),
                [a, b],
            )
        })
        .collect();
    spans.sort_unstable_by(|u, v| u.0.total_cmp(&v.0));
    for (i, &(_, x1, y0, y1, [a, b])) in spans.iter().enumerate() {
        let (p, q) = (node(nodes, a), node(nodes, b));
        for &(u0, _, v0, v1, [c, d]) in spans.iter().skip(i + 1) {
            if u0 > x1 {
                break;
            }
            let shared = [c, d]
                .iter()
                .any(|&v| point(v) == point(a) || point(v) == point(b));
            if v0 > y1 || v1 < y0 || shared {
                continue;
            }
            let (r, t) = (node(nodes, c), node(nodes, d));
            let (sr, st) = (side(p, q, r), side(p, q, t));
            let along = sr == 0.0 && st == 0.0;
            if !along && sr * st <= 0.0 && side(r, t, p) * side(r, t, q) <= 0.0 {
                return Err(MeshError::BoundaryCrossing {
                    edges: [[a, b], [c, d]],
                });
            }
        }
    }
    Ok(())
}

/// Every piece of the mesh (triangles joined through their nodes) reached by an electrode; a
/// floating piece left the factorisation to fail on a singular system, said as conductivities
/// spanning too many powers of ten.
pub(super) fn check_connected(
    n: usize,
    triangles: &[[usize; 3]],
    electrodes: &[Vec<[usize; 2]>],
    point: &[Option<usize>],
) -> Result<(), MeshError> {
    // Union-find over the nodes, halving paths.
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while let Some(&p) = parent.get(v)
            && p != v
        {
            let up = parent.get(p).copied().unwrap_or(p);
            if let Some(slot) = parent.get_mut(v) {
                *slot = up;
            }
            v = up;
        }
        v
    }
    for &[a, b, c] in triangles {
        for (u, v) in [(a, b), (b, c)] {
            let (ru, rv) = (root(&mut parent, u), root(&mut parent, v));
            if let Some(slot) = parent.get_mut(ru) {
                *slot = rv;
            }
        }
    }
    let mut reached = vec![false; n];
    let on_electrodes = electrodes
        .iter()
        .flatten()
        .flatten()
        .chain(point.iter().flatten());
    for &v in on_electrodes {
        let r = root(&mut parent, v);
        if let Some(slot) = reached.get_mut(r) {
            *slot = true;
        }
    }
    let piece: Vec<usize> = triangles.iter().map(|t| root(&mut parent, t[0])).collect();
    match piece
        .iter()
        .position(|&r| !reached.get(r).copied().unwrap_or(true))
    {
        Some(triangle) => Err(MeshError::Floating {
            triangle,
            triangles: piece
                .iter()
                .filter(|&&r| Some(&r) == piece.get(triangle))
                .count(),
        }),
        None => Ok(()),
    }
}

/// Each electrode's node when it is a point electrode (only `[i, i]` entries, all the same
/// node); an electrode that mixes a single node with edges refused.
pub(super) fn point_electrodes(
    electrodes: &[Vec<[usize; 2]>],
) -> Result<Vec<Option<usize>>, MeshError> {
    let point: Vec<Option<usize>> = electrodes
        .iter()
        .map(|el| {
            let first = el.first()?[0];
            el.iter()
                .all(|&[a, b]| a == first && b == first)
                .then_some(first)
        })
        .collect();
    let mixed = electrodes
        .iter()
        .zip(&point)
        .position(|(el, p)| p.is_none() && el.iter().any(|&[a, b]| a == b));
    if let Some(l) = mixed {
        return Err(MeshError::MixedElectrode { electrode: l });
    }
    Ok(point)
}

/// Each node under one electrode at most: two that share a node are shorted together.
pub(super) fn check_unshared(
    n: usize,
    electrodes: &[Vec<[usize; 2]>],
    point: &[Option<usize>],
) -> Result<(), MeshError> {
    let mut owner = vec![None; n];
    for (l, (edges, p)) in electrodes.iter().zip(point).enumerate() {
        let under: Vec<usize> = match p {
            Some(i) => vec![*i],
            None => edges.iter().flatten().copied().collect(),
        };
        for i in under {
            match owner.get_mut(i) {
                Some(Some(other)) if *other != l => {
                    return Err(MeshError::SharedNode {
                        electrodes: [*other, l],
                        node: i,
                    });
                }
                Some(o) => *o = Some(l),
                None => {}
            }
        }
    }
    Ok(())
}

/// An electrode's centre node: of the nodes of its `edges`, the one nearest their mean.
pub(super) fn centre_node(nodes: &[[f64; 2]], edges: &[[usize; 2]]) -> usize {
    let mut v: Vec<usize> = edges.iter().flatten().copied().collect();
    v.sort_unstable();
    v.dedup();
    let k = v.len() as f64;
    let c = v.iter().fold([0.0, 0.0], |[sx, sy], &i| {
        let [x, y] = node(nodes, i);
        [sx + x / k, sy + y / k]
    });
    v.iter()
        .copied()
        .min_by(|&a, &b| dist(node(nodes, a), c).total_cmp(&dist(node(nodes, b), c)))
        .unwrap_or(0)
}

/// What the finite elements need of a mesh's topology, each with its cause named: every
/// triangle once (a repeated one doubles its conductance), every node in a triangle (an unused
/// node makes the system singular), no triangles over others ([`check_overlap`]), and every electrode edge an edge of exactly one triangle,
/// the boundary (an edge inside the mesh, or nodes out of order along an electrode, changed
/// the voltages by up to 84 % without a word).
pub(super) fn check_topology(
    nodes: &[[f64; 2]],
    triangles: &[[usize; 3]],
    electrodes: &[Vec<[usize; 2]>],
    point: &[Option<usize>],
) -> Result<(), MeshError> {
    let n = nodes.len();
    let mut seen: HashMap<[usize; 3], usize> = HashMap::with_capacity(triangles.len());
    let mut edges: HashMap<[usize; 2], u32> = HashMap::with_capacity(2 * triangles.len());
    let mut used = vec![false; n];
    let edge = |a: usize, b: usize| [a.min(b), a.max(b)];
    for (i, t) in triangles.iter().enumerate() {
        let mut key = *t;
        key.sort_unstable();
        if let Some(j) = seen.insert(key, i) {
            return Err(MeshError::RepeatedTriangle {
                triangle: i,
                first: j,
            });
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
        return Err(MeshError::UnusedNode { node: v });
    }
    // (Before the boundary is read from the edges: one laid over others is not one.)
    check_overlap(nodes, triangles)?;
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
    let mut boundary_edges: Vec<[usize; 2]> = (edges.iter())
        .filter(|(_, count)| **count == 1)
        .map(|(e, _)| *e)
        .collect();
    boundary_edges.sort_unstable();
    check_boundary_uncrossed(nodes, &boundary_edges)?;
    let on_boundary = |v: usize| boundary.get(v).copied().unwrap_or(false);
    for (l, p) in point.iter().enumerate() {
        if let Some(v) = *p
            && !on_boundary(v)
        {
            return Err(MeshError::InteriorNode {
                electrode: l,
                node: v,
            });
        }
    }
    for (l, el) in electrodes.iter().enumerate() {
        for &[a, b] in el {
            match edges.get(&edge(a, b)) {
                Some(1) => {}
                Some(_) => {
                    return Err(MeshError::InteriorEdge {
                        electrode: l,
                        edge: [a, b],
                    });
                }
                None => {
                    return Err(MeshError::NotAnEdge {
                        electrode: l,
                        nodes: [a, b],
                    });
                }
            }
        }
    }
    Ok(())
}
