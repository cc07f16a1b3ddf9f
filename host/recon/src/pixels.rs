//! Pixel grids over a mesh: images drawn on pixels cost one small product per frame.

use nalgebra::DMatrix;

use crate::mesh::Mesh;
use crate::onestep::{OneStep, ReconError};

/// A pixel grid over a mesh: which triangle each pixel centre lies in.
#[derive(Clone, Debug)]
pub struct PixelGrid {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// Lower-left corner and pixel size, m: pixel (i, j) (column i, row j from the bottom)
    /// is centred at (x0 + (i + 1/2) size, y0 + (j + 1/2) size).
    pub origin: [f64; 2],
    /// Pixel size, m.
    pub size: f64,
    /// Triangle under each pixel (row-major from the bottom row), None outside the sheet.
    pub triangle: Vec<Option<usize>>,
}

impl PixelGrid {
    /// A grid `pixels` across the mesh's longer side.
    #[must_use]
    pub fn new(mesh: &Mesh, pixels: usize) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &mesh.nodes {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]) / pixels.max(1) as f64;
        let width = ((hi[0] - lo[0]) / size).round().max(1.0) as usize;
        let height = ((hi[1] - lo[1]) / size).round().max(1.0) as usize;
        let mut triangle = vec![None; width * height];
        // Each triangle claims the pixel centres inside it (barycentric test on its box).
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = tri.map(|i| mesh.nodes[i]);
            let bx = |d: usize, f: fn(f64, f64) -> f64| f(f(p[0][d], p[1][d]), p[2][d]);
            let i0 = (((bx(0, f64::min) - lo[0]) / size - 0.5).ceil().max(0.0)) as usize;
            let i1 = (((bx(0, f64::max) - lo[0]) / size - 0.5).floor().max(-1.0) + 1.0) as usize;
            let j0 = (((bx(1, f64::min) - lo[1]) / size - 0.5).ceil().max(0.0)) as usize;
            let j1 = (((bx(1, f64::max) - lo[1]) / size - 0.5).floor().max(-1.0) + 1.0) as usize;
            let area2 = mesh.double_area(t);
            for j in j0..j1.min(height) {
                for i in i0..i1.min(width) {
                    let c = [
                        lo[0] + (i as f64 + 0.5) * size,
                        lo[1] + (j as f64 + 0.5) * size,
                    ];
                    let w = |a: [f64; 2], b: [f64; 2]| {
                        ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])) / area2
                    };
                    let eps = -1e-12;
                    if w(p[0], p[1]) >= eps && w(p[1], p[2]) >= eps && w(p[2], p[0]) >= eps {
                        triangle[j * width + i].get_or_insert(t);
                    }
                }
            }
        }
        Self {
            width,
            height,
            origin: lo,
            size,
            triangle,
        }
    }

    /// Centre of pixel `index`, m.
    #[must_use]
    pub fn centre(&self, index: usize) -> [f64; 2] {
        let (i, j) = (index % self.width, index / self.width);
        [
            self.origin[0] + (i as f64 + 0.5) * self.size,
            self.origin[1] + (j as f64 + 0.5) * self.size,
        ]
    }

    /// The 4 neighbours of pixel `index` (left, right, below, above; None off the grid).
    #[must_use]
    pub fn neighbours(&self, index: usize) -> [Option<usize>; 4] {
        let (i, j) = (index % self.width, index / self.width);
        [
            (i > 0).then(|| index - 1),
            (i + 1 < self.width).then(|| index + 1),
            (j > 0).then(|| index - self.width),
            (j + 1 < self.height).then(|| index + self.width),
        ]
    }

    /// Mean of the centres of `pixels`, m ([0, 0] for none).
    #[must_use]
    pub fn centroid(&self, pixels: &[usize]) -> [f64; 2] {
        let n = pixels.len().max(1) as f64;
        pixels.iter().fold([0.0; 2], |c, &p| {
            let x = self.centre(p);
            [c[0] + x[0] / n, c[1] + x[1] / n]
        })
    }

    /// The reconstruction matrix onto the pixels (one row per pixel inside the sheet, in
    /// pixel order): a live frame then costs pixels x K multiply-adds.
    #[must_use]
    pub fn project(&self, r: &OneStep) -> DMatrix<f32> {
        let inside: Vec<usize> = self.triangle.iter().filter_map(|t| *t).collect();
        r.rows_f32(&inside)
    }

    /// A live frame onto the pixels: `projection` ([`PixelGrid::project`], pixels x K) times
    /// `dv` (K values, V) with faer's f32 kernel, into `out` (one value per pixel inside).
    ///
    /// # Errors
    /// [`ReconError::Parameter`] when `dv` does not hold K values or `out` not one per row.
    pub fn apply(projection: &DMatrix<f32>, dv: &[f32], out: &mut [f32]) -> Result<(), ReconError> {
        let (p, k) = projection.shape();
        if dv.len() != k || out.len() != p {
            return Err(ReconError::Parameter(format!(
                "{} values into {} pixels for a projection of {p} x {k}",
                dv.len(),
                out.len()
            )));
        }
        faer::linalg::matmul::matmul(
            faer::MatMut::from_column_major_slice_mut(out, p, 1),
            faer::Accum::Replace,
            faer::MatRef::from_column_major_slice(projection.as_slice(), p, k),
            faer::MatRef::from_column_major_slice(dv, k, 1),
            1.0,
            faer::Par::Seq,
        );
        Ok(())
    }

    /// Spreads per-triangle values onto the grid (None outside the sheet).
    #[must_use]
    pub fn image(&self, per_triangle: &[f64]) -> Vec<Option<f64>> {
        self.triangle
            .iter()
            .map(|t| t.map(|t| per_triangle[t]))
            .collect()
    }
}
