//! A sheet's outline as the mesh samples it (where the electrodes lie, how finely each stretch
//! is cut) and the refinement regions' lattices.

use et_core::sheet::{ElectrodeModel, Sheet};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use super::{MeshError, MeshSize, Refinement, dist, not_placed};

impl Refinement {
    /// Refused unless its centre is finite, its radius and edge positive, it adds at most a
    /// million points and it meets the sheet `spec`.
    pub(super) fn check(&self, spec: &Sheet) -> Result<(), MeshError> {
        let r = self;
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(r.radius) && ok(r.edge) && r.centre.iter().all(|c| c.is_finite())) {
            return Err(MeshError::Refinement {
                centre: r.centre,
                radius: r.radius,
                edge: r.edge,
            });
        }
        // A disc under 1e-4 of the sheet's size refines nothing a frame can show (as a
        // touch of that size): 1e-12 m was meshed without a word.
        let [x_min, y_min, x_max, y_max] = spec.shape.bounds();
        let least = 1e-4 * (x_max - x_min).max(y_max - y_min);
        if r.radius < least {
            return Err(MeshError::RefinementTooSmall {
                radius: r.radius,
                least,
            });
        }
        if (r.radius / r.edge).powi(2) > 1e6 {
            return Err(MeshError::RefinementTooFine {
                radius: r.radius,
                edge: r.edge,
                limit: "a million",
            });
        }
        if !spec.shape.contains(r.centre, 0.0)
            && spec.shape.distance_to_outline(r.centre) >= r.radius
        {
            return Err(MeshError::RefinementOffSheet {
                centre: r.centre,
                radius: r.radius,
            });
        }
        Ok(())
    }

    /// Seeds `cdt` with a triangular lattice of this region's edge (at most `interior`, m)
    /// over its disc on the sheet, leaving points closer than half an edge (or half the
    /// electrodes' edge `h_e`) to the outline to the boundary sampling.
    pub(super) fn seed(
        &self,
        cdt: &mut ConstrainedDelaunayTriangulation<Point2<f64>>,
        spec: &Sheet,
        interior: f64,
        h_e: f64,
    ) -> Result<(), MeshError> {
        let r = self;
        let [x_min, y_min, x_max, y_max] = spec.shape.bounds();
        let h = r.edge.min(interior);
        let dy = h * 0.75f64.sqrt();
        // The lattice over the part of the disc's square on the sheet's bounding box (a disc
        // far larger than the sheet costs no more than the sheet).
        let (c_x, c_y) = (r.centre[0], r.centre[1]);
        let span = |lo: f64, hi: f64, step: f64| {
            (
                (lo / step).floor() as i64 - 1,
                (hi / step).ceil() as i64 + 1,
            )
        };
        let (j_lo, j_hi) = span((-r.radius).max(y_min - c_y), r.radius.min(y_max - c_y), dy);
        let (i_lo, i_hi) = span((-r.radius).max(x_min - c_x), r.radius.min(x_max - c_x), h);
        if (j_hi - j_lo).max(0) as f64 * (i_hi - i_lo).max(0) as f64 > 1e7 {
            return Err(MeshError::RefinementTooFine {
                radius: r.radius,
                edge: h,
                limit: "ten million",
            });
        }
        for j in j_lo..=j_hi {
            let y = j as f64 * dy;
            let shift = if j % 2 == 0 { 0.0 } else { 0.5 * h };
            for i in i_lo..=i_hi {
                let x = i as f64 * h + shift;
                let p = [r.centre[0] + x, r.centre[1] + y];
                if x.hypot(y) <= r.radius
                    && spec.shape.contains(p, 0.0)
                    && spec.shape.distance_to_outline(p) > 0.5 * h.max(h_e)
                {
                    cdt.insert(Point2::new(p[0], p[1])).map_err(not_placed)?;
                }
            }
        }
        Ok(())
    }
}

/// Where the electrodes lie along a sheet's outline and how finely the outline is sampled.
pub(super) struct Outline {
    /// Point electrodes (a node each), else the complete model's (a stretch of outline each).
    pub(super) point: bool,
    /// Each electrode's centre, as a fraction of the outline's arc.
    pub(super) centres: Vec<f64>,
    /// Each electrode's graded stretch [start, end), arc fractions (end may pass 1).
    pub(super) spans: Vec<(f64, f64)>,
    /// The outline's length, m.
    pub(super) perimeter: f64,
    /// Half a stretch, arc fraction.
    pub(super) half: f64,
    /// The edge length along a stretch, m.
    pub(super) h_e: f64,
    /// Pieces either side of a point electrode's node.
    pub(super) pieces: f64,
}

impl Outline {
    /// The outline of `spec` meshed at `size`; [`MeshError::Overlap`] when two electrodes'
    /// stretches overlap.
    pub(super) fn of(spec: &Sheet, size: MeshSize) -> Result<Self, MeshError> {
        let perimeter = spec.shape.perimeter();
        let half = 0.5 * spec.electrodes.width / perimeter;
        if !(half > 0.0 && half.is_finite()) {
            return Err(MeshError::ElectrodeWidth);
        }
        let point = spec.electrodes.model == ElectrodeModel::Point;
        let centres = spec.electrodes.arc_positions(&spec.shape);
        // The graded stretch of outline at each electrode: its width for the complete model;
        // for point electrodes an interior edge either side of the node (or a quarter of the
        // spacing, if less), which only sets where the outline is sampled finer.
        let half = if point {
            let spacing = 1.0 / centres.len().max(1) as f64;
            (size.interior / perimeter).min(0.25 * spacing)
        } else {
            half
        };
        // Electrode intervals in arc fraction [start, end), end may pass 1.
        let mut spans: Vec<(f64, f64)> = centres
            .iter()
            .map(|&t| {
                let t = t.rem_euclid(1.0);
                (t - half, t + half)
            })
            .collect();
        let mut order: Vec<usize> = (0..spans.len()).collect();
        order.sort_by(|&a, &b| spans[a].0.total_cmp(&spans[b].0));
        for w in 0..order.len() {
            let (a, b) = (order[w], order[(w + 1) % order.len()]);
            let next_start = spans[b].0 + if w + 1 == order.len() { 1.0 } else { 0.0 };
            if spans[a].1 >= next_start {
                return Err(MeshError::Overlap { electrode: a });
            }
        }
        for s in &mut spans {
            if s.0 < 0.0 {
                *s = (s.0 + 1.0, s.1 + 1.0);
            }
        }
        let h_e = if point {
            size.electrode.min(half * perimeter)
        } else {
            size.electrode.min(spec.electrodes.width)
        };
        // Point electrodes: each side of a node is cut into the same number of pieces, so its
        // fan's rings end on outline nodes.
        let pieces = (half * perimeter / h_e * (1.0 - 1e-9)).ceil().max(1.0);
        Ok(Self {
            point,
            centres,
            spans,
            perimeter,
            half,
            h_e,
            pieces,
        })
    }

    /// Whether arc fraction `t` lies on an electrode's stretch.
    fn under(&self, t: f64) -> bool {
        self.spans.iter().any(|&(a, b)| {
            let t = if t < a { t + 1.0 } else { t };
            t >= a && t <= b
        })
    }

    /// The outline's sample points, arc fractions in order: corners and stretch ends kept,
    /// the electrodes' edge along the stretches and the interior edge elsewhere.
    pub(super) fn samples(&self, spec: &Sheet, size: MeshSize) -> Vec<f64> {
        // Breakpoints: corners and electrode ends, in arc order.
        let mut breaks: Vec<(f64, bool)> = spec
            .shape
            .corners()
            .iter()
            .map(|&c| (spec.shape.arc_of(c), false))
            .collect();
        for (&(a, b), &c) in self.spans.iter().zip(&self.centres) {
            breaks.push((a.rem_euclid(1.0), true));
            if self.point {
                breaks.push((c.rem_euclid(1.0), true)); // the point electrode's node
            }
            breaks.push((b.rem_euclid(1.0), false));
        }
        breaks.sort_by(|a, b| a.0.total_cmp(&b.0));
        breaks.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-12);
        let half_len = self.half * self.perimeter;
        let mut ts: Vec<f64> = Vec::new();
        for i in 0..breaks.len() {
            let a = breaks[i].0;
            let b = if i + 1 == breaks.len() {
                breaks[0].0 + 1.0
            } else {
                breaks[i + 1].0
            };
            let h = if self.under(0.5 * (a + b)) {
                self.h_e
            } else {
                size.interior
            };
            let len = (b - a) * self.perimeter;
            let n = if self.point && (len - half_len).abs() < 1e-9 * half_len {
                self.pieces
            } else {
                (len / h * (1.0 - 1e-9)).ceil().max(1.0)
            } as usize;
            ts.extend((0..n).map(|k| a + (b - a) * k as f64 / n as f64));
        }
        ts
    }

    /// Each electrode's boundary edges in the triangulation (`nodes` its vertices) and its
    /// node nearest its centre; [`MeshError::EmptyElectrode`] for an electrode with none.
    #[allow(clippy::type_complexity)]
    pub(super) fn electrodes(
        &self,
        cdt: &ConstrainedDelaunayTriangulation<Point2<f64>>,
        spec: &Sheet,
        nodes: &[[f64; 2]],
    ) -> Result<(Vec<Vec<[usize; 2]>>, Vec<usize>), MeshError> {
        // Each span's boundary edges: the electrode (complete model), or where the point
        // electrode's node is.
        let mut in_span = vec![Vec::new(); self.spans.len()];
        for e in cdt.undirected_edges() {
            if !e.is_constraint_edge() {
                continue;
            }
            let [a, b] = e.vertices();
            let (pa, pb) = (a.position(), b.position());
            let mid = spec
                .shape
                .arc_of([0.5 * (pa.x + pb.x), 0.5 * (pa.y + pb.y)]);
            if let Some(l) = self.spans.iter().position(|&(s, t)| {
                let m = if mid < s { mid + 1.0 } else { mid };
                m > s && m < t
            }) {
                in_span[l].push([a.fix().index(), b.fix().index()]);
            }
        }
        if let Some(l) = in_span.iter().position(Vec::is_empty) {
            return Err(MeshError::EmptyElectrode { electrode: l });
        }
        // The electrode's node nearest its centre (the point model's node lies exactly there).
        let centre_nodes: Vec<usize> = self
            .centres
            .iter()
            .zip(&in_span)
            .map(|(&t, edges)| {
                let c = spec.shape.boundary_point(t);
                edges
                    .iter()
                    .flatten()
                    .copied()
                    .min_by(|&a, &b| dist(nodes[a], c).total_cmp(&dist(nodes[b], c)))
                    .unwrap_or(0)
            })
            .collect();
        // A point electrode is its node; its two boundary edges stand for it (drawing, checks).
        let electrodes = if self.point {
            in_span
                .iter()
                .zip(&centre_nodes)
                .map(|(edges, c)| edges.iter().copied().filter(|e| e.contains(c)).collect())
                .collect()
        } else {
            in_span
        };
        Ok((electrodes, centre_nodes))
    }
}
