//! Regions of interest and touches in an image
//! (docs/method.md §6.5): pixels above a share of the
//! image's maximum, split at their saddles, kept where they stand out of the noise.

use crate::pixels::PixelGrid;

/// The largest value of an image when it is positive and finite.
fn positive_max(image: &[Option<f64>]) -> Option<f64> {
    let max = largest_of(image, |v| v);
    (max.is_finite() && max > 0.0).then_some(max)
}

/// The largest `f(v)` over an image's values (NaN skipped, -inf for none), in eight running
/// maxima: no chain of comparisons each waiting for the one before (a pass over 4 096 pixels
/// is read several times a frame).
fn largest_of(image: &[Option<f64>], f: impl Fn(f64) -> f64) -> f64 {
    let mut m = [f64::NEG_INFINITY; 8];
    let (runs, rest) = image.as_chunks::<8>();
    for run in runs {
        for j in 0..8 {
            if let Some(v) = run[j] {
                let x = f(v);
                if x > m[j] {
                    m[j] = x;
                }
            }
        }
    }
    for v in rest.iter().flatten() {
        let x = f(*v);
        if x > m[0] {
            m[0] = x;
        }
    }
    m.into_iter().fold(f64::NEG_INFINITY, f64::max)
}

/// The ROI threshold f of docs/method.md §6 [3.10] the reference study used for a protocol: 0.10 for
/// adjacent (and opposite, which it did not report), 0.08 for pseudo-polar, 0.05 for PP-PP.
#[must_use]
pub fn default_threshold(kind: et_core::protocol::ProtocolKind) -> f64 {
    use et_core::protocol::ProtocolKind;
    match kind {
        ProtocolKind::PseudoPolar => 0.08,
        ProtocolKind::PpPp => 0.05,
        _ => 0.10,
    }
}

/// One connected region of an image above threshold.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Region {
    /// Centroid of its pixels, m.
    pub centroid: [f64; 2],
    /// Area, m^2.
    pub area: f64,
    /// Largest value in it.
    pub peak: f64,
    /// The pixel (index into the image) where it peaks.
    pub peak_pixel: usize,
    /// Its largest value over its pixel's noise, where [`touches`] was given the noise.
    pub z: Option<f64>,
    /// Its pixels (indices into the image), to draw its outline; not serialised.
    #[serde(skip)]
    pub pixels: Vec<usize>,
}

impl Region {
    /// The mesh refinement this region asks for: a disc of its area, widened as
    /// [`Refinement::touch`] widens a touch (to re-mesh where an image found something).
    ///
    /// [`Refinement::touch`]: crate::mesh::Refinement::touch
    #[must_use]
    pub fn refinement(&self) -> crate::mesh::Refinement {
        crate::mesh::Refinement::touch(self.centroid, (self.area / std::f64::consts::PI).sqrt())
    }
}

/// The regions of interest (docs/method.md §6 [3.10]): pixels >= f max(image) (for a touch, which
/// raises the conductivity), grouped into 4-connected regions, largest peak first.
#[must_use]
pub fn regions(grid: &PixelGrid, image: &[Option<f64>], f: f64) -> Vec<Region> {
    let Some(max) = positive_max(image) else {
        return Vec::new();
    };
    let keep: Vec<bool> = image
        .iter()
        .map(|v| v.is_some_and(|v| v >= f * max))
        .collect();
    let mut seen = vec![false; keep.len()];
    let mut out = Vec::new();
    for start in 0..keep.len() {
        if !keep[start] || seen[start] {
            continue;
        }
        let (mut stack, mut members) = (vec![start], Vec::new());
        seen[start] = true;
        while let Some(p) = stack.pop() {
            members.push(p);
            for q in grid.neighbours(p).into_iter().flatten() {
                if keep[q] && !seen[q] {
                    seen[q] = true;
                    stack.push(q);
                }
            }
        }
        let (peak_pixel, peak) = members.iter().filter_map(|&m| Some((m, image[m]?))).fold(
            (start, f64::NEG_INFINITY),
            |a, b| if b.1 > a.1 { b } else { a },
        );
        out.push(Region {
            centroid: grid.centroid(&members),
            area: members.len() as f64 * grid.size * grid.size,
            peak,
            peak_pixel,
            z: None,
            pixels: members,
        });
    }
    out.sort_by(|a, b| b.peak.total_cmp(&a.peak));
    out
}

/// How deep the dip below the lower of two peaks must be, as a share of the image's
/// largest value, for [`touches`] to keep them apart.
pub const PROMINENCE: f64 = 0.25;

/// The touches in an image: the regions of interest of [`regions`] (pixels >= f max,
/// docs/method.md §6.5 [3.10]), each split at its saddles into one region per peak that stands out.
///
/// A threshold alone answers docs/method.md §8's "several ROIs" only when the image dips below it
/// between the touches; under noise the alpha that suits the data often joins two touches
/// over a saddle far above f max. Here the pixels are flooded from the top (a watershed):
/// when two rising regions meet at a pixel of value v, the lower one (peak h) stays a touch
/// of its own when its prominence h - v is at least `prominence` x max(image), else it joins
/// the higher one (so ripples and noise on a touch's flank stay part of it). Later pixels
/// join their highest-peaked neighbouring region. Each touch's area is its share of the
/// region of interest; its centroid is that of its pixels at or above half its peak, so the
/// flank it shares with a neighbour does not pull it over. With `sd`, the standard deviation
/// of each pixel's noise ([`OneStep::noise_sd`] on the grid; empty when unknown), each touch
/// also gets its largest value over noise, `z`, for [`above_noise`]. Largest peak first.
#[must_use]
pub fn touches(
    grid: &PixelGrid,
    image: &[Option<f64>],
    sd: &[Option<f64>],
    f: f64,
    prominence: f64,
) -> Vec<Region> {
    touches_with(grid, image, f, prominence, |p| sd.get(p).copied().flatten())
}

/// The touches et finds, in `et reconstruct` and in the live pipeline (`et stream`, `et
/// view`) alike: [`touches`] at [`PROMINENCE`], each kept when it reaches `z` times its
/// pixels' noise somewhere ([`above_noise`]; [`TOUCH_Z`] by default). `sd(p)` is pixel p's
/// noise standard deviation (None: unknown), asked only for the pixels of a region, so a
/// caller that pays for each pixel's noise pays for those alone.
#[must_use]
pub fn touch_rule(
    grid: &PixelGrid,
    image: &[Option<f64>],
    f: f64,
    z: f64,
    sd: impl PixelNoise,
) -> Vec<Region> {
    let mut found = touches_with(grid, image, f, PROMINENCE, sd);
    found.retain(|r| r.z.is_none_or(|v| v >= z));
    found
}

/// Each pixel's noise standard deviation, for [`touch_rule`]: a closure `|p| sd` is one.
pub trait PixelNoise {
    /// Pixel p's noise standard deviation (None: unknown).
    fn sd(&mut self, p: usize) -> Option<f64>;

    /// A lower bound of [`sd`](Self::sd) that costs less to have (by default the standard
    /// deviation itself): a region's z, its largest value over noise, is then made from the
    /// pixels whose bound could beat the best so far, not from every pixel's own noise.
    fn floor(&mut self, p: usize) -> Option<f64> {
        self.sd(p)
    }
}

impl<F: FnMut(usize) -> Option<f64>> PixelNoise for F {
    fn sd(&mut self, p: usize) -> Option<f64> {
        self(p)
    }
}

/// The largest `image[q] / sd(q)` over `pixels` (those with a positive noise), as the
/// exhaustive maximum gives it; each pixel's own noise made only when its value over the
/// noise's floor (an upper bound of its z, for a value above 0) could beat the best so far.
fn region_z(pixels: &[usize], image: &[Option<f64>], noise: &mut impl PixelNoise) -> Option<f64> {
    // Each pixel's bound: v / floor >= v / sd for v > 0; 0 for v <= 0 (v / sd <= 0); no
    // bound without a floor. None: no value, which the exhaustive maximum skips too.
    let bounds: Vec<Option<f64>> = pixels
        .iter()
        .map(|&q| {
            let v = image.get(q).copied().flatten()?;
            Some(if v <= 0.0 {
                0.0
            } else {
                (noise.floor(q).filter(|&s| s > 0.0)).map_or(f64::INFINITY, |lo| v / lo)
            })
        })
        .collect();
    let mut best: Option<f64> = None;
    let mut exact = |q: usize, best: &mut Option<f64>| {
        let Some(z) = noise
            .sd(q)
            .filter(|&s| s > 0.0)
            .and_then(|s| Some(image.get(q).copied().flatten()? / s))
        else {
            return;
        };
        *best = Some(best.map_or(z, |b| b.max(z)));
    };
    // The most promising pixel first, then whichever could still beat it.
    let first = (0..pixels.len())
        .filter(|&i| bounds[i].is_some())
        .max_by(|&a, &b| {
            bounds[a]
                .unwrap_or(0.0)
                .total_cmp(&bounds[b].unwrap_or(0.0))
        });
    if let Some(i) = first {
        exact(pixels[i], &mut best);
    }
    for (i, &q) in pixels.iter().enumerate() {
        if Some(i) == first {
            continue;
        }
        match (bounds[i], best) {
            (Some(b), Some(z)) if b <= z => {}
            (Some(_), _) => exact(q, &mut best),
            // No value here: the exhaustive maximum skips it too.
            (None, _) => {}
        }
    }
    best
}

/// [`touches`] with each pixel's noise from `sd` (None: unknown).
fn touches_with(
    grid: &PixelGrid,
    image: &[Option<f64>],
    f: f64,
    prominence: f64,
    sd: impl PixelNoise,
) -> Vec<Region> {
    match positive_max(image) {
        Some(max) => touches_below(grid, image, max, f, prominence, sd),
        None => Vec::new(),
    }
}

/// [`touches_with`] of an image whose largest value, positive and finite, is `max`.
fn touches_below(
    grid: &PixelGrid,
    image: &[Option<f64>],
    max: f64,
    f: f64,
    prominence: f64,
    mut sd: impl PixelNoise,
) -> Vec<Region> {
    let mut order: Vec<(usize, f64)> = image
        .iter()
        .enumerate()
        .filter_map(|(p, v)| v.filter(|&v| v >= f * max).map(|v| (p, v)))
        .collect();
    order.sort_unstable_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    // Union-find over the flooded pixels by rank (their place in `order`): a pixel is
    // flooded once the flood has passed its rank, and a root's peak is its region's highest
    // value. Only the pixels at or above f max are held, not the whole grid.
    let mut rank = vec![u32::MAX; image.len()];
    for (i, &(p, _)) in order.iter().enumerate() {
        rank[p] = i as u32;
    }
    let mut parent: Vec<usize> = (0..order.len()).collect();
    let mut peak = vec![f64::NAN; order.len()];
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    // Pairs of regions already found to be separate touches (by root).
    let mut apart: Vec<(usize, usize)> = Vec::new();
    for (i, &(p, v)) in order.iter().enumerate() {
        // The regions already flooded around p (at most its four neighbours'), on the stack,
        // highest peak first.
        let (mut around, mut n) = ([0usize; 4], 0);
        for q in grid.neighbours(p).into_iter().flatten() {
            let j = rank[q] as usize;
            if j < i {
                let r = root(&mut parent, j);
                if !around[..n].contains(&r) {
                    // Insertion by peak, descending.
                    let at = around[..n]
                        .iter()
                        .position(|&a| peak[r] > peak[a])
                        .unwrap_or(n);
                    around.copy_within(at..n, at + 1);
                    around[at] = r;
                    n += 1;
                }
            }
        }
        let near = &around[..n];
        let Some(&top) = near.first() else {
            peak[i] = v;
            continue;
        };
        parent[i] = top;
        for &r in &near[1..] {
            let separate = apart
                .iter()
                .any(|&(a, b)| (a, b) == (r, top) || (a, b) == (top, r))
                || peak[r] - v >= prominence * max;
            if separate {
                if !apart.contains(&(r, top)) {
                    apart.push((r, top));
                }
            } else {
                parent[r] = top;
                // What was apart from r is now apart from top.
                for pair in &mut apart {
                    for end in [&mut pair.0, &mut pair.1] {
                        if *end == r {
                            *end = top;
                        }
                    }
                }
            }
        }
    }
    // Each region's pixels, by root (a noisy image has many small regions).
    let mut slot = vec![usize::MAX; order.len()];
    let mut members: Vec<(usize, Vec<usize>)> = Vec::new();
    for (i, &(p, _)) in order.iter().enumerate() {
        let r = root(&mut parent, i);
        if slot[r] == usize::MAX {
            slot[r] = members.len();
            members.push((r, Vec::new()));
        }
        members[slot[r]].1.push(p);
    }
    let mut out: Vec<Region> = members
        .into_iter()
        .map(|(r, m)| {
            let top = peak[r];
            let core: Vec<usize> = m
                .iter()
                .copied()
                .filter(|&q| image[q].is_some_and(|v| v >= 0.5 * top))
                .collect();
            Region {
                centroid: grid.centroid(&core),
                area: m.len() as f64 * grid.size * grid.size,
                peak: top,
                peak_pixel: order[r].0,
                z: region_z(&m, image, &mut sd),
                pixels: m,
            }
        })
        .collect();
    out.sort_by(|a, b| b.peak.total_cmp(&a.peak));
    out
}

/// A touch stands out of the noise when its peak is at least this many times the noise of
/// its pixel (see [`above_noise`]; noise alone stays below about 3.5 on the simulator).
pub const TOUCH_Z: f64 = 5.0;

/// The share of a difference image's largest magnitude an object of either sign must reach:
/// a one-step image's side lobes (the ringing of the opposite sign around a strong object,
/// and specks at the boundary) reach 10 to 20 % of its peak (`cargo run --release -p et-host
/// --example defaults_sweep`, docs/measurements.md), true second and third objects 30 to 100 %.
pub const OBJECT_FRACTION: f64 = 0.25;

/// The share of the heaviest object's mass (its image's magnitude summed over its pixels) an
/// object must reach. The data fix an inclusion's mass better than its peak, which sharpens
/// as alpha falls: at the small alphas a real tank's frames want, the boundary's specks and
/// the ringing between two targets pass [`OBJECT_FRACTION`] with one to fifteen pixels, under
/// 2 % of a true object's mass, while true second and third objects weigh 25 % and more.
/// 0.05 keeps a speck on the 16-electrode tank, 0.1 and 0.2 count alike on both tanks and on
/// the simulated ones (docs/measurements.md, "Defaults on real tanks"); the smaller is kept,
/// for weak touches beside strong ones.
pub const OBJECT_MASS_FRACTION: f64 = 0.1;

/// An object of a difference image: a touch-like region of either sign, conductive (+1: a
/// press, a metal rod) or resistive (-1: a plastic rod, a cut).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Object {
    /// +1 where the conductivity rose, -1 where it fell.
    pub sign: i8,
    /// The region (its peak's magnitude: `peak` is |Delta sigma| at its strongest pixel).
    pub region: Region,
}

/// An object as `et reconstruct --json` reports it (its `objects`), and the Python module
/// too: SI, the peak relative to the background. Field names are fixed: scripts rely on them.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ObjectSummary {
    /// Its centroid, m.
    pub x_m: f64,
    /// Its centroid, m.
    pub y_m: f64,
    /// +1 conductive (the conductivity rose), -1 resistive.
    pub sign: i8,
    /// Its area above the threshold, m^2.
    pub area_m2: f64,
    /// Its peak Delta sigma / sigma_0 (dimensionless, signed: the change over the
    /// background's conductivity).
    pub peak: f64,
    /// Its peak over the pixel's noise (None when the noise is not known).
    pub z: Option<f64>,
}

impl ObjectSummary {
    /// `object` on a background of conductivity `sigma0` (S per square).
    #[must_use]
    pub fn of(object: &Object, sigma0: f64) -> Self {
        Self::of_region(&object.region, object.sign, sigma0)
    }

    /// A region of `sign` (a touch or region of an image is +1) on a background of
    /// conductivity `sigma0` (S per square).
    #[must_use]
    pub fn of_region(r: &Region, sign: i8, sigma0: f64) -> Self {
        Self {
            x_m: r.centroid[0],
            y_m: r.centroid[1],
            sign,
            area_m2: r.area,
            peak: f64::from(sign) * r.peak / sigma0,
            z: r.z,
        }
    }
}

/// The objects of a signed image: [`touches`] of the image and of its negative, each kept
/// above `f` times the image's largest magnitude (so that the ringing around a strong object
/// of one sign is not taken for an object of the other), `z` times its noise and
/// [`OBJECT_MASS_FRACTION`] of the heaviest object's mass, strongest (largest |peak|) first.
#[must_use]
pub fn objects(
    grid: &PixelGrid,
    image: &[Option<f64>],
    sd: &[Option<f64>],
    f: f64,
    z: f64,
) -> Vec<Object> {
    objects_with(grid, image, |p| sd.get(p).copied().flatten(), f, z)
}

/// [`objects`] with each pixel's noise from `sd`, asked for the pixels of a region alone (a
/// caller that pays for each pixel's noise pays for those).
#[must_use]
pub fn objects_with(
    grid: &PixelGrid,
    image: &[Option<f64>],
    mut sd: impl PixelNoise,
    f: f64,
    z: f64,
) -> Vec<Object> {
    // Each sign's largest value.
    let (rising, falling) = (largest_of(image, |v| v), largest_of(image, |v| -v));
    let largest = rising.max(falling);
    if !(largest > 0.0 && largest.is_finite()) {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (sign, max) in [(1i8, rising), (-1, falling)] {
        if max <= 0.0 {
            continue;
        }
        // touches() thresholds at f times this sign's maximum: rescale to the largest magnitude.
        let f_here = f * largest / max;
        if f_here > 1.0 {
            continue;
        }
        let negated: Vec<Option<f64>>;
        let signed = if sign > 0 {
            image
        } else {
            negated = image.iter().map(|v| v.map(|v| -v)).collect();
            &negated
        };
        let found = touches_below(grid, signed, max, f_here, PROMINENCE, Borrowed(&mut sd));
        out.extend(
            above_noise(&found, z)
                .into_iter()
                .map(|region| Object { sign, region }),
        );
    }
    // Each object's mass: the image's magnitude summed over its pixels.
    let mass = |o: &Object| -> f64 {
        o.region
            .pixels
            .iter()
            .filter_map(|&p| image[p])
            .map(f64::abs)
            .sum()
    };
    let heaviest = out.iter().map(mass).fold(0.0f64, f64::max);
    out.retain(|o| mass(o) >= OBJECT_MASS_FRACTION * heaviest);
    out.sort_by(|a, b| b.region.peak.total_cmp(&a.region.peak));
    out
}

impl PixelNoise for crate::pixels::RowNoise<'_> {
    fn sd(&mut self, p: usize) -> Option<f64> {
        crate::pixels::RowNoise::sd(self, p)
    }
}

/// A pixel noise lent to one call and used again after it.
struct Borrowed<'a, N>(&'a mut N);

impl<N: PixelNoise> PixelNoise for Borrowed<'_, N> {
    fn sd(&mut self, p: usize) -> Option<f64> {
        self.0.sd(p)
    }

    fn floor(&mut self, p: usize) -> Option<f64> {
        self.0.floor(p)
    }
}

/// The regions that reach at least `z` times their pixels' noise somewhere (their `z`, from
/// [`touches`]); a region whose noise is unknown is kept.
#[must_use]
pub fn above_noise(regions: &[Region], z: f64) -> Vec<Region> {
    regions
        .iter()
        .filter(|r| r.z.is_none_or(|v| v >= z))
        .cloned()
        .collect()
}
