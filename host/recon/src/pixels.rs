//! Pixel grids over a mesh: images drawn on pixels cost two thin products per frame.

use crate::mesh::Mesh;
use crate::onestep::OneStep;
use crate::operator::{FrameOperator, SquaredRows};

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

    /// The outline of the pixels `member` marks (one flag per pixel): each edge between a
    /// member and a non-member (or the grid's edge), as its two ends, m. Drawn as line
    /// segments it outlines a region of interest.
    #[must_use]
    pub fn outline(&self, member: &[bool]) -> Vec<[[f64; 2]; 2]> {
        let is = |p: Option<usize>| p.is_some_and(|p| member.get(p).copied().unwrap_or(false));
        let corner = |i: usize, j: usize| {
            [
                self.origin[0] + i as f64 * self.size,
                self.origin[1] + j as f64 * self.size,
            ]
        };
        let mut edges = Vec::new();
        for p in (0..self.width * self.height).filter(|&p| is(Some(p))) {
            let (i, j) = (p % self.width, p / self.width);
            let [left, right, below, above] = self.neighbours(p);
            for (next, a, b) in [
                (left, corner(i, j), corner(i, j + 1)),
                (right, corner(i + 1, j), corner(i + 1, j + 1)),
                (below, corner(i, j), corner(i + 1, j)),
                (above, corner(i, j + 1), corner(i + 1, j + 1)),
            ] {
                if !is(next) {
                    edges.push([a, b]);
                }
            }
        }
        edges
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

    /// The reconstruction matrix onto the triangles under the pixels, each once, and where
    /// each pixel reads its value: a frame costs the distinct triangles' rows, not one row
    /// per pixel (four pixels or more to a triangle at 750 triangles on 64 x 64 pixels).
    #[must_use]
    pub fn project_under(&self, r: &OneStep) -> PixelOperator {
        let mut under: Vec<usize> = self.triangle.iter().flatten().copied().collect();
        under.sort_unstable();
        under.dedup();
        let at = self
            .triangle
            .iter()
            .map(|t| t.and_then(|t| under.binary_search(&t).ok()))
            .collect();
        PixelOperator {
            rows: FrameOperator::of_rows(r, &under),
            at,
            squares: std::sync::OnceLock::new(),
        }
    }

    /// The reconstruction matrix onto the pixels (one row per pixel inside the sheet, in
    /// pixel order), as a [`FrameOperator`].
    #[must_use]
    pub fn project(&self, r: &OneStep) -> FrameOperator {
        let inside: Vec<usize> = self.triangle.iter().filter_map(|t| *t).collect();
        FrameOperator::of_rows(r, &inside)
    }

    /// Spreads per-triangle values onto the grid (None outside the sheet).
    #[must_use]
    pub fn image(&self, per_triangle: &[f64]) -> Vec<Option<f64>> {
        self.triangle
            .iter()
            .map(|t| t.map(|t| per_triangle[t]))
            .collect()
    }

    /// [`OneStep::noise_sd`] on the pixels for dV's variance `var_dv` (K values, V^2),
    /// computed for the triangles under them only.
    ///
    /// # Errors
    /// As [`OneStep::noise_sd_of`].
    pub fn noise_sd(
        &self,
        r: &OneStep,
        var_dv: &[f64],
    ) -> Result<Vec<Option<f64>>, crate::onestep::ReconError> {
        let mut under: Vec<usize> = self.triangle.iter().flatten().copied().collect();
        under.sort_unstable();
        under.dedup();
        let sd = r.noise_sd_of(var_dv, &under)?;
        Ok(self
            .triangle
            .iter()
            .map(|t| t.and_then(|t| under.binary_search(&t).ok().map(|i| sd[i])))
            .collect())
    }

    /// An image (one value per pixel, the bottom row first, as [`PixelGrid::image`] gives)
    /// as a picture is read: rows from the top, row-major (height x width), each value times
    /// `scale`, NaN outside the sheet. `plt.imshow` shows it upright.
    #[must_use]
    pub fn top_first(&self, image: &[Option<f64>], scale: f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.width * self.height);
        self.top_first_into(image, scale, &mut out);
        out
    }

    /// [`PixelGrid::top_first`] appended to `out` (a stack of images grows frame by frame).
    pub fn top_first_into(&self, image: &[Option<f64>], scale: f64, out: &mut Vec<f64>) {
        let start = out.len();
        out.resize(start + self.width * self.height, f64::NAN);
        self.top_first_onto(image, scale, &mut out[start..]);
    }

    /// [`PixelGrid::top_first`] written over `out` (height x width values; a longer `out`
    /// keeps the rest, a shorter one takes the rows it holds).
    pub fn top_first_onto(&self, image: &[Option<f64>], scale: f64, out: &mut [f64]) {
        for (j, to) in (0..self.height)
            .rev()
            .zip(out.chunks_mut(self.width.max(1)))
        {
            let row = image
                .get(j * self.width..(j + 1) * self.width)
                .unwrap_or(&[]);
            for (t, v) in to.iter_mut().zip(row) {
                *t = v.map_or(f64::NAN, |v| v * scale);
            }
            // A short image (not of this grid) is padded with NaN, as before.
            to.iter_mut().skip(row.len()).for_each(|t| *t = f64::NAN);
        }
    }
}

/// A frame onto the pixels through the triangles under them ([`PixelGrid::project_under`]).
#[derive(Clone, Debug)]
pub struct PixelOperator {
    /// One row per distinct triangle under a pixel (in increasing triangle order).
    rows: FrameOperator,
    /// Each pixel's row of `rows` (the grid's order), None outside the sheet.
    at: Vec<Option<usize>>,
    /// `rows`' entries squared (each pixel's noise), made on first use.
    squares: std::sync::OnceLock<SquaredRows>,
}

impl PixelOperator {
    /// The image of `dv` (K values, V) on the pixels, the grid's order (None outside).
    ///
    /// # Errors
    /// As [`FrameOperator::image`].
    pub fn image(&self, dv: &[f64]) -> Result<Vec<Option<f64>>, crate::onestep::ReconError> {
        let rows = self.rows.image(dv)?;
        Ok(self
            .at
            .iter()
            .map(|i| i.and_then(|i| rows.get(i).copied().map(f64::from)))
            .collect())
    }

    /// The image of `dv` (K values, V) drawn over `out` as [`PixelGrid::top_first_onto`]
    /// draws [`PixelOperator::image`]'s, `grid` the one this operator was made on: one pass
    /// from the rows' values.
    ///
    /// # Errors
    /// As [`FrameOperator::image`].
    pub fn picture(
        &self,
        grid: &PixelGrid,
        dv: &[f64],
        scale: f64,
        out: &mut [f64],
    ) -> Result<(), crate::onestep::ReconError> {
        let rows = self.rows.image(dv)?;
        let width = grid.width.max(1);
        for (j, to) in (0..grid.height).rev().zip(out.chunks_mut(width)) {
            let at = self.at.get(j * width..(j + 1) * width).unwrap_or(&[]);
            for (t, i) in to.iter_mut().zip(at) {
                *t = i
                    .and_then(|i| rows.get(i))
                    .map_or(f64::NAN, |v| f64::from(*v) * scale);
            }
            to.iter_mut().skip(at.len()).for_each(|t| *t = f64::NAN);
        }
        Ok(())
    }

    /// Each pixel's noise standard deviation (Delta sigma, S per square) under the channels'
    /// variances `var` (K values, V^2), from the operator's rows squared (made at the first
    /// call, kept): asked pixel by pixel, each triangle's once.
    #[must_use]
    pub fn noise(&self, var: &[f64]) -> RowNoise<'_> {
        RowNoise {
            squares: self.squares.get_or_init(|| SquaredRows::of(&self.rows)),
            at: &self.at,
            var: var.iter().map(|&v| v as f32).collect(),
            made: vec![None; self.rows.rows()],
        }
    }
}

/// Pixels' noise through [`PixelOperator::noise`] (a [`crate::PixelNoise`]).
#[derive(Debug)]
pub struct RowNoise<'a> {
    squares: &'a SquaredRows,
    at: &'a [Option<usize>],
    var: Vec<f32>,
    /// Each row's noise once made.
    made: Vec<Option<f64>>,
}

impl RowNoise<'_> {
    /// Pixel p's noise standard deviation (None outside the sheet).
    pub fn sd(&mut self, p: usize) -> Option<f64> {
        let row = self.at.get(p).copied().flatten()?;
        if let Some(sd) = self.made.get(row).copied().flatten() {
            return Some(sd);
        }
        let sd = self.squares.sd(row, &self.var)?;
        if let Some(slot) = self.made.get_mut(row) {
            *slot = Some(sd);
        }
        Some(sd)
    }
}
