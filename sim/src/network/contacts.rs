//! Where the electrodes meet the grid: the nodes each contact covers and its weight along the edge.

use super::*;

/// Places electrodes on the outline: electrode e covers the arc from `positions[e] - width/2`
/// to `positions[e] + width/2` (arc-length fractions of the perimeter, see
/// [`Shape::boundary_point`]). Each boundary node owns the stretch of outline half-way to its
/// neighbours along it; it joins the electrode with the share of the contact conductance
/// `1 / contact_ohm[e]` that its stretch overlaps the electrode, so an electrode's extent does
/// not jump with the resolution. An electrode narrower than the grid takes its nearest node.
#[must_use]
pub fn place_contacts(
    shape: &Shape,
    grid: &Grid,
    positions: &[f64],
    width: f64,
    contact_ohm: &[f64],
    sheet_resistance: f64,
) -> Vec<Contact> {
    let perimeter = shape.perimeter();
    let along = edge_layer(shape, grid);
    let m = along.len();
    // Each node's hat function along the outline: 1 at the node, falling linearly to 0 at
    // its two neighbours (wrapping). An electrode spread evenly over [lo, hi] gives node k the
    // integral of its hat over that interval: the measured potential is then the average of the
    // linearly interpolated potential under the electrode, smooth in the electrode's position.
    let hats: Vec<(f64, f64, f64, u32)> = (0..m)
        .map(|k| {
            let (s, n) = along[k];
            let prev = if k == 0 {
                along[m - 1].0 - perimeter
            } else {
                along[k - 1].0
            };
            let next = if k + 1 == m {
                along[0].0 + perimeter
            } else {
                along[k + 1].0
            };
            (prev, s, next, n)
        })
        .collect();
    positions
        .iter()
        .zip(contact_ohm)
        .map(|(&t, &z)| {
            let centre = t.rem_euclid(1.0) * perimeter;
            let (lo, hi) = (centre - width / 2.0, centre + width / 2.0);
            let weight = |&(a, s, b, _): &(f64, f64, f64, u32)| {
                [-perimeter, 0.0, perimeter]
                    .iter()
                    .map(|w| hat_integral(a + w, s + w, b + w, lo, hi))
                    .sum::<f64>()
            };
            // Shares below a millionth of the width are round-off of hats that end at the edge.
            let mut share: Vec<(u32, f64)> = hats
                .iter()
                .map(|h| (h.3, weight(h)))
                .filter(|&(_, o)| o > 1e-6 * width)
                .collect();
            if share.is_empty() {
                share = hats
                    .iter()
                    .min_by(|x, y| {
                        let d = |h: &(f64, f64, f64, u32)| {
                            (h.1 - centre)
                                .rem_euclid(perimeter)
                                .min((centre - h.1).rem_euclid(perimeter))
                        };
                        d(x).total_cmp(&d(y))
                    })
                    .map(|h| vec![(h.3, 1.0)])
                    .unwrap_or_default();
            }
            let total: f64 = share.iter().map(|s| s.1).sum();
            let g = 1.0 / z.max(CONTACT_MIN_RELATIVE * sheet_resistance);
            Contact {
                nodes: share.into_iter().map(|(n, o)| (n, g * o / total)).collect(),
            }
        })
        .collect()
}

/// The edge layer, one node deep: nodes inside the outline with a lattice neighbour outside it
/// (the cut-cell nodes outside carry only slivers of sheet), as (arc length in m, node),
/// sorted along the outline. Electrodes attach to these nodes.
#[must_use]
pub fn edge_layer(shape: &Shape, grid: &Grid) -> Vec<(f64, u32)> {
    let tol = 1e-9 * shape.size();
    let [hx, hy] = grid.spacing;
    let perimeter = shape.perimeter();
    let mut along: Vec<(f64, u32)> = (0..grid.len() as u32)
        .filter(|&n| {
            let p = grid.nodes[n as usize];
            shape.contains(p, tol)
                && [[hx, 0.0], [-hx, 0.0], [0.0, hy], [0.0, -hy]]
                    .iter()
                    .any(|d| !shape.contains([p[0] + d[0], p[1] + d[1]], tol))
        })
        .map(|n| (shape.arc_of(grid.nodes[n as usize]) * perimeter, n))
        .collect();
    along.sort_by(|a, b| a.0.total_cmp(&b.0));
    along
}

/// Integral over [lo, hi] of the hat that rises linearly from 0 at `a` to 1 at `s` and falls
/// back to 0 at `b`.
pub(super) fn hat_integral(a: f64, s: f64, b: f64, lo: f64, hi: f64) -> f64 {
    // Integral of a linear ramp f(x) = (x - x0) / (x1 - x0) over [max(lo, p), min(hi, q)].
    let ramp = |p: f64, q: f64, x0: f64, x1: f64| {
        let (u, v) = (lo.max(p), hi.min(q));
        if v <= u || x1 == x0 {
            return 0.0;
        }
        let f = |x: f64| (x - x0) / (x1 - x0);
        (v - u) * (f(u) + f(v)) / 2.0
    };
    ramp(a, s, a, s) + ramp(s, b, b, s)
}
