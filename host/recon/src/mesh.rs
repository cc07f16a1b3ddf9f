//! Triangle meshes of a sheet for the finite elements (docs/method.md §5): the outline sampled with
//! every corner and every electrode end as a vertex, electrodes as runs of boundary edges,
//! constrained Delaunay triangulation and quality refinement by `spade`.
//!
//! Sizes are in metres. The boundary is sampled finer under the electrodes (where the
//! complete electrode model's current concentrates) than elsewhere, regions of interest
//! ([`Refinement`]: a touch, or a region an image found) are seeded with a lattice of their
//! own spacing, and the refinement's angle limit grades the elements from there into the
//! interior, so a mesh is fine only where the scene needs it.

use et_core::sheet::{ElectrodeModel, Sheet};
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

/// A triangle mesh with electrodes on its boundary.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Node coordinates, m.
    pub nodes: Vec<[f64; 2]>,
    /// Triangles as node indices, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
    /// Per electrode, the boundary edges (node pairs) under it.
    pub electrodes: Vec<Vec<[usize; 2]>>,
    /// Per electrode, the node at its centre (the point-electrode model's node).
    pub centre_nodes: Vec<usize>,
}

/// How fine to mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshSize {
    /// Largest edge length in the interior, m.
    pub interior: f64,
    /// Boundary edge length under electrodes, m (complete electrode model: at most the
    /// electrode's width, so an electrode is one edge or more; point electrodes: near the
    /// electrode's node, within an interior edge of it).
    pub electrode: f64,
    /// Smallest angle the refinement aims for, degrees (spade guarantees up to about 30).
    pub min_angle_deg: f64,
    /// Point electrodes: how many rings of the regular fan around each electrode's node
    /// (0: none; at most one fewer than the boundary edges either side of the node). Ring k
    /// has radius k d (d the boundary edge there) and 3 k edges, so the fan's triangles are
    /// nearly equilateral and every electrode sees the same mesh, mirror-symmetric about its
    /// normal: the discretisation error of the point source's singularity, which dominates
    /// the voltages of the other electrodes, is then 2 to 3 times smaller at the same count
    /// of triangles (docs/measurements.md, "Convergence"). Ignored by the complete model.
    pub fan_rings: usize,
}

impl MeshSize {
    /// About `triangles` triangles on `spec`'s outline, electrodes sampled 4 times finer
    /// than the interior.
    #[must_use]
    pub fn for_count(spec: &Sheet, triangles: usize) -> Self {
        // An equilateral triangle of edge h has area h^2 sqrt(3)/4.
        let h = (4.0 * spec.shape.area() / (3f64.sqrt() * triangles.max(1) as f64)).sqrt();
        Self {
            interior: h,
            electrode: h / 4.0,
            min_angle_deg: 28.0,
            fan_rings: 3,
        }
    }
}

/// A disc of the sheet meshed finer than the rest (a touch, or a region of interest an
/// image found): edges of about `edge` inside, graded into the coarser interior around it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refinement {
    /// Centre, m.
    pub centre: [f64; 2],
    /// Radius, m.
    pub radius: f64,
    /// Edge length inside, m.
    pub edge: f64,
}

impl Refinement {
    /// What a touch of `radius` (m) at `centre` needs: its disc and a margin of half its
    /// radius, at a quarter of its radius, so the edge of the pressed area is resolved.
    #[must_use]
    pub fn touch(centre: [f64; 2], radius: f64) -> Self {
        Self {
            centre,
            radius: 1.5 * radius,
            edge: 0.25 * radius,
        }
    }
}

impl Mesh {
    /// Meshes `spec`'s outline with its electrodes (width `spec.electrodes.width`).
    ///
    /// # Errors
    /// [`MeshError`] for bad sizes, overlapping electrodes or a failed triangulation.
    pub fn of_sheet(spec: &Sheet, size: MeshSize) -> Result<Self, MeshError> {
        Self::refined(spec, size, &[])
    }

    /// As [`Mesh::of_sheet`], and finer in `regions`: each is seeded with a triangular
    /// lattice of its edge length (points closer than half an edge to the outline are left
    /// to the boundary sampling), and the quality refinement grades away from it.
    ///
    /// # Errors
    /// As [`Mesh::of_sheet`]; a region with a non-finite or non-positive radius or edge is
    /// [`MeshError::Refinement`], one that would add more than a million points
    /// [`MeshError::RefinementTooFine`], one off the sheet [`MeshError::RefinementOffSheet`].
    pub fn refined(
        spec: &Sheet,
        size: MeshSize,
        regions: &[Refinement],
    ) -> Result<Self, MeshError> {
        for r in regions {
            r.check(spec)?;
        }
        spec.shape.validate()?;
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(size.interior) && ok(size.electrode) && size.min_angle_deg.is_finite()) {
            return Err(MeshError::Sizes {
                interior: size.interior,
                electrode: size.electrode,
                min_angle_deg: size.min_angle_deg,
            });
        }
        let outline = Outline::of(spec, size)?;
        let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
        let mut handles = Vec::new();
        for t in outline.samples(spec, size) {
            let p = spec.shape.boundary_point(t);
            handles.push(cdt.insert(Point2::new(p[0], p[1])).map_err(not_placed)?);
        }
        for i in 0..handles.len() {
            let (a, b) = (handles[i], handles[(i + 1) % handles.len()]);
            if a != b {
                cdt.add_constraint(a, b);
            }
        }
        if outline.point {
            let d = outline.half * outline.perimeter / outline.pieces;
            let rings = size.fan_rings.min(outline.pieces as usize - 1);
            for &t in &outline.centres {
                for p in fan(&spec.shape, t, d, rings) {
                    cdt.insert(Point2::new(p[0], p[1])).map_err(not_placed)?;
                }
            }
        }
        for r in regions {
            r.seed(&mut cdt, spec, size.interior, outline.h_e)?;
        }
        let max_area = 3f64.sqrt() / 4.0 * size.interior * size.interior;
        let result = cdt.refine(
            RefinementParameters::<f64>::new()
                .exclude_outer_faces(true)
                .with_max_allowed_area(max_area)
                .with_angle_limit(AngleLimit::from_deg(size.min_angle_deg.clamp(0.0, 30.0)))
                .with_max_additional_vertices(50_000_000),
        );
        let nodes: Vec<[f64; 2]> = cdt
            .vertices()
            .map(|v| [v.position().x, v.position().y])
            .collect();
        let triangles: Vec<[usize; 3]> = cdt
            .inner_faces()
            .filter(|f| !result.excluded_faces.contains(&f.fix()))
            .map(|f| f.vertices().map(|v| v.fix().index()))
            .collect();
        let (electrodes, centre_nodes) = outline.electrodes(&cdt, spec, &nodes)?;
        Ok(Self {
            nodes,
            triangles,
            electrodes,
            centre_nodes,
        })
    }

    /// A mesh of about `triangles` triangles: within 10 % where a search over the sizes
    /// reaches it, else the closest found. The interior edge and the electrodes' edge (a
    /// quarter of it) are scaled together, bracketing the count; when the electrodes' grading
    /// alone needs more triangles than the budget (coarse meshes of many electrodes), the
    /// refinement's smallest angle is relaxed from 28 to 20 degrees, then point electrodes'
    /// fans lose rings, then the angle goes down to 15 degrees, so budgets from
    /// 200 triangles up are met within 15 % on the reference sheets (`cargo run --release -p
    /// et-recon --example mesh_budget`).
    ///
    /// # Errors
    /// As [`Mesh::of_sheet`].
    pub fn with_about(spec: &Sheet, triangles: usize) -> Result<Self, MeshError> {
        Self::with_about_refined(spec, triangles, &[])
    }

    /// As [`Mesh::with_about`], with `regions` refined as in [`Mesh::refined`]: the same
    /// budget of triangles, spent where the regions need it (the interior elsewhere is
    /// coarser to pay for them).
    ///
    /// # Errors
    /// As [`Mesh::refined`].
    pub fn with_about_refined(
        spec: &Sheet,
        triangles: usize,
        regions: &[Refinement],
    ) -> Result<Self, MeshError> {
        let target = triangles.max(1) as f64;
        let miss = |m: &Mesh| (m.triangles.len() as f64 / target).ln().abs();
        let mut best: Option<Mesh> = None;
        let point = spec.electrodes.model == ElectrodeModel::Point;
        // A fan of k rings holds about 3 k^2 triangles: at most 40 % of the budget.
        let electrodes = f64::from(spec.electrodes.count.max(1));
        let affordable = (0.4 * target / (3.0 * electrodes)).sqrt().floor() as usize;
        let full = MeshSize::for_count(spec, triangles)
            .fan_rings
            .min(affordable);
        // Smaller angles down to 20 degrees before fewer fan rings (at a small budget the
        // rings buy more accuracy than the angle: `cargo bench -p et-recon --bench peer`),
        // then 15 degrees without rings.
        let rings = if point { full } else { 0 };
        let tries = (0..=rings)
            .rev()
            .flat_map(|r| [28.0, 25.0, 20.0].map(|a| (r, a)))
            .chain([(0, 15.0)]);
        for (fan_rings, angle) in tries {
            let base = MeshSize {
                min_angle_deg: angle,
                fan_rings,
                ..MeshSize::for_count(spec, triangles)
            };
            // Scale s of both edge lengths; the count falls roughly as s^-2. `fine` and
            // `coarse` bracket the target once both sides have been seen.
            let (mut scale, mut fine, mut coarse) = (1.0f64, 0.0f64, f64::INFINITY);
            for _ in 0..10 {
                let size = MeshSize {
                    interior: base.interior * scale,
                    electrode: base.electrode * scale,
                    ..base
                };
                let mesh = Self::refined(spec, size, regions)?;
                let ratio = mesh.triangles.len() as f64 / target;
                if best.as_ref().is_none_or(|b| miss(&mesh) < miss(b)) {
                    best = Some(mesh);
                }
                if (ratio - 1.0).abs() < 0.1 {
                    break;
                }
                if ratio > 1.0 {
                    fine = fine.max(scale);
                } else {
                    coarse = coarse.min(scale);
                }
                let next = scale * ratio.sqrt();
                scale = if next > fine && next < coarse {
                    next
                } else if coarse.is_finite() && fine > 0.0 {
                    (fine * coarse).sqrt()
                } else {
                    // Past a floor the count no longer follows the size: stop this angle.
                    break;
                };
            }
            if best.as_ref().is_some_and(|b| miss(b) < 0.1f64.ln_1p()) {
                break;
            }
        }
        best.ok_or(MeshError::NoMesh)
    }

    /// Twice the signed area of triangle `t` (positive: counter-clockwise), m^2.
    #[must_use]
    pub fn double_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t].map(|i| self.nodes[i]);
        (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
    }

    /// Centroid of triangle `t`, m.
    #[must_use]
    pub fn centroid(&self, t: usize) -> [f64; 2] {
        let [a, b, c] = self.triangles[t].map(|i| self.nodes[i]);
        [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0]
    }

    /// Total length of electrode `l`'s edges, m.
    #[must_use]
    pub fn electrode_length(&self, l: usize) -> f64 {
        self.electrodes[l]
            .iter()
            .map(|&[a, b]| dist(self.nodes[a], self.nodes[b]))
            .sum()
    }

    /// Smallest interior angle over all triangles, degrees.
    #[must_use]
    pub fn min_angle_deg(&self) -> f64 {
        self.triangles
            .iter()
            .flat_map(|t| {
                let p = t.map(|i| self.nodes[i]);
                (0..3).map(move |k| {
                    let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
                    let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
                    (u[0] * v[1] - u[1] * v[0])
                        .abs()
                        .atan2(u[0] * v[0] + u[1] * v[1])
                        .to_degrees()
                })
            })
            .fold(180.0, f64::min)
    }
}

/// The regular fan around a point electrode at arc fraction `t` of `shape`'s outline: rings
/// k = 1..=`rings` of radius k `d` (m) about the electrode's node, ring k cut into 3 k equal
/// arcs whose inner points (the ends lie on the outline, which is sampled at `d` there) are
/// returned. Points outside the sheet or within 0.3 d of its outline (a curved or cornered
/// outline) are left out.
fn fan(shape: &et_core::sheet::shape::Shape, t: f64, d: f64, rings: usize) -> Vec<[f64; 2]> {
    let c = shape.boundary_point(t);
    let (a, b) = (
        shape.boundary_point(t - 1e-7),
        shape.boundary_point(t + 1e-7),
    );
    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
    if rings == 0 || len.is_nan() || len <= 0.0 {
        return Vec::new();
    }
    let tangent = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
    // The normal pointing into the sheet.
    let mut normal = [-tangent[1], tangent[0]];
    if !shape.contains(
        [c[0] + 1e-3 * d * normal[0], c[1] + 1e-3 * d * normal[1]],
        0.0,
    ) {
        normal = [-normal[0], -normal[1]];
    }
    let mut points = Vec::new();
    for k in 1..=rings {
        let rho = k as f64 * d;
        for j in 1..3 * k {
            let (sin, cos) = (std::f64::consts::PI * j as f64 / (3 * k) as f64).sin_cos();
            let p = [
                c[0] + rho * (cos * tangent[0] + sin * normal[0]),
                c[1] + rho * (cos * tangent[1] + sin * normal[1]),
            ];
            if shape.contains(p, 0.0) && shape.distance_to_outline(p) > 0.3 * d {
                points.push(p);
            }
        }
    }
    points
}

mod error;
pub mod import;
mod outline;
pub use error::MeshError;
use outline::Outline;

pub(crate) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// A point the triangulation could not place, in words.
pub(crate) fn not_placed(e: spade::InsertionError) -> MeshError {
    MeshError::Triangulation(match e {
        spade::InsertionError::NAN => "a point is not a number",
        spade::InsertionError::TooLarge => "a coordinate is too large (the sheet in m?)",
        spade::InsertionError::TooSmall => "a coordinate is too small to place",
    })
}
