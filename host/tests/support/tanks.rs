//! Two real saline tanks measured by other labs' instruments, read from
//! `../shared/data/tanks/` (beside the project's root; not part of the repository), written
//! out as a user of `et reconstruct` writes them (a scene, a protocol file, a frames CSV), and
//! scored: the strongest object's distance to the nearest target, its sign, the object count.
//!
//! - kit4-2017: the "Open 2D Electrical Impedance Tomography data archive", Hauptmann,
//!   Kolehmainen, Mach, Savolainen, Seppanen, Siltanen (2017), arXiv:1704.01178, measured with
//!   the KIT4 system in Kuopio: a 28 cm disc, 16 electrodes, 79 injections, 1 264 values.
//! - ktc2023-training: the Kuopio Tomography Challenge 2023 (Finnish Inverse Problems Society
//!   and the University of Eastern Finland), its public training data (Zenodo record
//!   8252370): a 23 cm disc, 32 electrodes, 76 injections, 2 356 values.
//!
//! Shared by the regression test (`host/tests/tanks.rs`) and the table's example
//! (`host/examples/tanks.rs`).

#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// One target of a case: a rod from the tank's floor to the surface.
#[derive(Clone, Debug)]
pub struct Target {
    /// Its centroid, m.
    pub centre: [f64; 2],
    /// Metal (the conductivity rose) or plastic.
    pub conductive: bool,
    /// The radius of a disc of its area, m.
    pub radius: f64,
}

/// One measured case with known targets.
#[derive(Clone, Debug)]
pub struct Case {
    /// The data set's name for it.
    pub id: String,
    /// Its frame's index in [`Tank::frames_csv`] (the reference is frame 0).
    pub frame: usize,
    /// The frame, V.
    pub values: Vec<f32>,
    pub targets: Vec<Target>,
}

/// A tank as a user describes it to et, with its cases.
#[derive(Clone, Debug)]
pub struct Tank {
    pub name: &'static str,
    /// The tank's radius, m.
    pub radius: f64,
    pub electrodes: u16,
    /// The scene's text (its protocol in `protocol.csv` beside it).
    pub scene: String,
    /// The protocol file: one row per frame value, electrodes counted from 1.
    pub protocol_csv: String,
    /// The homogeneous tank's frame, V.
    pub reference: Vec<f32>,
    pub cases: Vec<Case>,
    /// Where the data set lies.
    pub dir: PathBuf,
}

/// The folder of the real tanks beside the project, when it is there.
#[must_use]
pub fn root() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/tanks");
    dir.is_dir().then_some(dir)
}

fn rows(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(|c| c.trim().to_string()).collect())
        .collect()
}

fn numbers(path: &Path) -> Vec<Vec<f64>> {
    rows(path)
        .into_iter()
        .map(|r| {
            r.iter()
                .map(|c| {
                    c.parse()
                        .unwrap_or_else(|_| panic!("{}: '{c}'", path.display()))
                })
                .collect()
        })
        .collect()
}

/// Both tanks (None when `../shared/data/tanks` is not beside the project).
#[must_use]
pub fn both() -> Option<Vec<Tank>> {
    let root = root()?;
    Some(vec![
        load(
            &root.join("kit4-2017"),
            "kit4-2017 (16 electrodes)",
            0.14,
            0.025,
            1e-3,
        ),
        load(
            &root.join("ktc2023-training"),
            "ktc2023-training (32 electrodes)",
            0.115,
            0.0113,
            1e-3,
        ),
    ])
}

/// A tank's folder (the layout of `../shared/data/tanks/README.md`): a disc of `radius` (m)
/// with electrodes `width` (m) wide; the injections' amplitudes in units of `unit_a` A.
#[must_use]
pub fn load(dir: &Path, name: &'static str, radius: f64, width: f64, unit_a: f64) -> Tank {
    // Where electrode 1 sits and which way the numbers run, from electrodes.csv's angles.
    let angles: Vec<f64> = rows(&dir.join("electrodes.csv"))[1..]
        .iter()
        .map(|r| r[1].parse().expect("an angle"))
        .collect();
    let electrodes = u16::try_from(angles.len()).expect("electrodes");
    let step = (angles[1] - angles[0] + 540.0).rem_euclid(360.0) - 180.0;
    let direction = if step > 0.0 { "ccw" } else { "cw" };
    let injections: Vec<(u16, u16, f64)> = rows(&dir.join("injection_pairs.csv"))[1..]
        .iter()
        .map(|r| {
            (
                r[1].parse().expect("source"),
                r[2].parse().expect("sink"),
                r[3].parse::<f64>().expect("amplitude") * unit_a,
            )
        })
        .collect();
    let measurements: Vec<(u16, u16)> = rows(&dir.join("measurement_pairs.csv"))[1..]
        .iter()
        .map(|r| (r[1].parse().expect("plus"), r[2].parse().expect("minus")))
        .collect();
    let mut protocol_csv = String::from("source,sink,positive,negative,current_a\n");
    for (source, sink, current) in &injections {
        for (plus, minus) in &measurements {
            protocol_csv.push_str(&format!("{source},{sink},{plus},{minus},{current:e}\n"));
        }
    }
    let scene = format!(
        "description = \"{name}: a real saline tank (../shared/data/tanks)\"\n\n[sheet]\n\
         shape = {{ kind = \"disc\", radius = {radius} }}\n\
         electrodes = {{ count = {electrodes}, width = {width}, contact_ohm = 20, first_deg = {}, \
         direction = \"{direction}\" }}\n\n[scan]\nprotocol = {{ file = \"protocol.csv\", base = 1 }}\n",
        angles[0]
    );
    let f32s = |r: &[f64]| r.iter().map(|&v| v as f32).collect::<Vec<f32>>();
    let reference = f32s(&numbers(&dir.join("reference.csv"))[0]);
    let voltages = numbers(&dir.join("voltages.csv"));
    let samples = rows(&dir.join("samples.csv"));
    let truth = rows(&dir.join("ground_truth_objects.csv"));
    let mut cases = Vec::new();
    for (row, sample) in samples[1..].iter().enumerate() {
        let id = &sample[1];
        let targets: Vec<Target> = truth[1..]
            .iter()
            .filter(|t| &t[0] == id)
            .map(|t| Target {
                centre: [t[3].parse().expect("x"), t[4].parse().expect("y")],
                conductive: t[2] == "conductive",
                radius: t[6].parse().expect("radius"),
            })
            .collect();
        if targets.is_empty() {
            continue;
        }
        cases.push(Case {
            id: id.clone(),
            frame: row + 1,
            values: f32s(&voltages[row]),
            targets,
        });
    }
    Tank {
        name,
        radius,
        electrodes,
        scene,
        protocol_csv,
        reference,
        cases,
        dir: dir.to_path_buf(),
    }
}

impl Tank {
    /// The frames file a user would write: the reference first, then every row of
    /// voltages.csv (a case's frame is its [`Case::frame`]).
    #[must_use]
    pub fn frames_csv(&self) -> String {
        let mut out = String::new();
        let line = |v: &[f32]| {
            v.iter()
                .map(|x| format!("{x:e}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        out.push_str(&line(&self.reference));
        out.push('\n');
        for row in numbers(&self.dir.join("voltages.csv")) {
            let v: Vec<f32> = row.iter().map(|&x| x as f32).collect();
            out.push_str(&line(&v));
            out.push('\n');
        }
        out
    }

    /// Writes scene.toml, protocol.csv and frames.csv into `dir`; returns the scene's and the
    /// frames' paths.
    pub fn write(&self, dir: &Path) -> (PathBuf, PathBuf) {
        std::fs::create_dir_all(dir).expect("a folder");
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, &self.scene).expect("scene");
        std::fs::write(dir.join("protocol.csv"), &self.protocol_csv).expect("protocol");
        let frames = dir.join("frames.csv");
        std::fs::write(&frames, self.frames_csv()).expect("frames");
        (scene, frames)
    }
}

/// One object as scored: its centre (m) and sign (+1 conductive).
#[derive(Clone, Copy, Debug)]
pub struct Found {
    pub centre: [f64; 2],
    pub sign: i8,
}

/// A case's score.
#[derive(Clone, Debug)]
pub struct CaseScore {
    /// The strongest object's distance to the nearest target, m (None: no object).
    pub miss: Option<f64>,
    /// Whether its sign is that target's.
    pub sign_right: bool,
    /// Objects found against targets.
    pub found: usize,
    pub targets: usize,
}

impl CaseScore {
    /// `objects` (strongest first) against `case`'s targets.
    #[must_use]
    pub fn of(case: &Case, objects: &[Found]) -> Self {
        let first = objects.first();
        let nearest = first.map(|o| {
            case.targets
                .iter()
                .map(|t| {
                    (
                        (t.centre[0] - o.centre[0]).hypot(t.centre[1] - o.centre[1]),
                        t,
                    )
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .expect("a target")
        });
        Self {
            miss: nearest.map(|n| n.0),
            sign_right: match (first, nearest) {
                (Some(o), Some((_, t))) => (o.sign > 0) == t.conductive,
                _ => false,
            },
            found: objects.len(),
            targets: case.targets.len(),
        }
    }

    /// The object count within one of the targets'.
    #[must_use]
    pub fn count_within_one(&self) -> bool {
        self.found.abs_diff(self.targets) <= 1
    }
}

/// A set of cases' summary: the median miss (m; infinite when half found nothing), signs
/// right, counts within one.
#[derive(Clone, Copy, Debug)]
pub struct Summary {
    pub median_miss: f64,
    pub sign_right: usize,
    pub count_within_one: usize,
    pub cases: usize,
}

#[must_use]
pub fn summary(scores: &[CaseScore]) -> Summary {
    let mut misses: Vec<f64> = scores
        .iter()
        .map(|s| s.miss.unwrap_or(f64::INFINITY))
        .collect();
    misses.sort_by(f64::total_cmp);
    let n = misses.len();
    let median_miss = match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => misses[n / 2],
        _ => 0.5 * (misses[n / 2 - 1] + misses[n / 2]),
    };
    Summary {
        median_miss,
        sign_right: scores.iter().filter(|s| s.sign_right).count(),
        count_within_one: scores.iter().filter(|s| s.count_within_one()).count(),
        cases: n,
    }
}

impl Summary {
    /// The bar of et's defaults on real tanks: the median miss at most 5 mm, the sign right in
    /// all but one case, the count within one in at least 80 % of cases.
    #[must_use]
    pub fn meets_the_bar(&self) -> bool {
        self.median_miss <= 5e-3
            && self.sign_right + 1 >= self.cases
            && 5 * self.count_within_one >= 4 * self.cases
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.1} mm, sign {}/{}, count {}/{}",
            1e3 * self.median_miss,
            self.sign_right,
            self.cases,
            self.count_within_one,
            self.cases
        )
    }
}

/// The side of the score's square grid, pixels (the Kuopio Tomography Challenge 2023's).
pub const SCORE_PIXELS: usize = 256;

/// The truth of a case on the score's grid ([`score_pixel`]; 0 water, 1 resistive, 2
/// conductive): the Kuopio Tomography Challenge 2023's own image where the tank has one
/// (`truth/<case>.csv`), else each target drawn as the disc of its area at its centroid (the
/// KIT4 archive gives the masks' centroids and areas).
#[must_use]
pub fn truth_mask(tank: &Tank, case: &Case) -> Vec<u8> {
    let path = tank.dir.join("truth").join(format!("{}.csv", case.id));
    if path.is_file() {
        let rows = numbers(&path);
        return rows.iter().flatten().map(|&v| v as u8).collect();
    }
    let n = SCORE_PIXELS;
    (0..n * n)
        .map(|p| {
            let [x, y] = score_pixel(tank.radius, p / n, p % n);
            case.targets
                .iter()
                .find(|t| (x - t.centre[0]).hypot(y - t.centre[1]) <= t.radius)
                .map_or(0, |t| if t.conductive { 2 } else { 1 })
        })
        .collect()
}

/// The centre of pixel (r, c) of the score's grid over a tank of `radius`, m: the square
/// [-radius, radius]^2 in [`SCORE_PIXELS`] x [`SCORE_PIXELS`], row 0 at the top (the
/// challenge's grid of its 23 cm tank).
#[must_use]
pub fn score_pixel(radius: f64, r: usize, c: usize) -> [f64; 2] {
    let h = 2.0 * radius / SCORE_PIXELS as f64;
    [
        -radius + (c as f64 + 0.5) * h,
        radius - (r as f64 + 0.5) * h,
    ]
}

/// An image on et's pixel grid sampled at the score's grid over the tank (None outside the
/// tank or the image), each score pixel taking the value of et's pixel under its centre.
#[must_use]
pub fn on_score_grid<T: Copy>(
    tank: &Tank,
    grid: &et_recon::PixelGrid,
    image: &[Option<T>],
) -> Vec<Option<T>> {
    let n = SCORE_PIXELS;
    (0..n * n)
        .map(|p| {
            let [x, y] = score_pixel(tank.radius, p / n, p % n);
            if x.hypot(y) > tank.radius {
                return None;
            }
            let i = ((x - grid.origin[0]) / grid.size).floor();
            let j = ((y - grid.origin[1]) / grid.size).floor();
            if i < 0.0 || j < 0.0 {
                return None;
            }
            let (i, j) = (i as usize, j as usize);
            (i < grid.width && j < grid.height)
                .then(|| image[j * grid.width + i])
                .flatten()
        })
        .collect()
}

/// A `.npy` image `et reconstruct` wrote of `tank` (--image-out, --segment: f64, top row
/// first, NaN outside) sampled on the score's grid ([`on_score_grid`]), from the grid `et
/// reconstruct --json` reported with it.
#[must_use]
pub fn read_pixels(tank: &Tank, path: &Path, grid: &serde_json::Value) -> Vec<Option<f64>> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let n = |k: &str| grid[k].as_u64().unwrap_or_else(|| panic!("grid: {k}")) as usize;
    let x = |k: &str| grid[k].as_f64().unwrap_or_else(|| panic!("grid: {k}"));
    let (rows, cols) = (n("rows"), n("cols"));
    let data = &bytes[bytes.len() - 8 * rows * cols..];
    let value = |r: usize, c: usize| {
        let at = 8 * (r * cols + c);
        let v = f64::from_le_bytes(data[at..at + 8].try_into().expect("8 bytes"));
        (!v.is_nan()).then_some(v)
    };
    // Bottom row first, as et's pixel grids are.
    let bottom_first: Vec<Option<f64>> = (0..rows)
        .rev()
        .flat_map(|r| (0..cols).map(move |c| (r, c)))
        .map(|(r, c)| value(r, c))
        .collect();
    let grid = et_recon::PixelGrid {
        width: cols,
        height: rows,
        origin: [x("x0_m"), x("y0_m")],
        size: x("pixel_m"),
        triangle: Vec::new(),
    };
    on_score_grid(tank, &grid, &bottom_first)
}

/// A Gaussian blur as the challenge's score makes it: exp(-d^2 / (2 x 80^2)) over 321 x 321
/// pixels, 'same' size, separable.
fn blur(image: &[f64], n: usize) -> Vec<f64> {
    let sigma = 80.0f64;
    let half = 160isize;
    let w: Vec<f64> = (-half..=half)
        .map(|d| (-(d * d) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let pass = |src: &[f64], along_rows: bool| -> Vec<f64> {
        let mut out = vec![0.0; n * n];
        for r in 0..n {
            for c in 0..n {
                let mut s = 0.0;
                for (k, wk) in w.iter().enumerate() {
                    let d = k as isize - half;
                    let (rr, cc) = if along_rows {
                        (r as isize, c as isize + d)
                    } else {
                        (r as isize + d, c as isize)
                    };
                    if rr >= 0 && cc >= 0 && (rr as usize) < n && (cc as usize) < n {
                        s += wk * src[rr as usize * n + cc as usize];
                    }
                }
                out[r * n + c] = s;
            }
        }
        out
    };
    pass(&pass(image, true), false)
}

/// The challenge's score of a segmentation `seg` against `truth` (both 256 x 256, 0 water, 1
/// resistive, 2 conductive): the mean over the two classes of the SSIM of their masks
/// (`../shared/data/tanks/README.md`, "The challenge's own score"); 1 is perfect.
#[must_use]
pub fn challenge_score(truth: &[u8], seg: &[u8]) -> f64 {
    let n = SCORE_PIXELS;
    static ONES: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    let ones = ONES.get_or_init(|| blur(&vec![1.0; n * n], n));
    let local =
        |v: &[f64]| -> Vec<f64> { blur(v, n).iter().zip(ones).map(|(a, b)| a / b).collect() };
    let (c1, c2) = (1e-4, 9e-4);
    let mut total = 0.0;
    for class in [1u8, 2] {
        let mask = |image: &[u8]| -> Vec<f64> {
            image
                .iter()
                .map(|&v| f64::from(u8::from(v == class)))
                .collect()
        };
        let (t, r) = (mask(truth), mask(seg));
        // The masks are 0 or 1: t^2 = t, so the local mean of t^2 is mu_t (and of r^2, mu_r).
        let (mt, mr) = (local(&t), local(&r));
        let tr = local(&t.iter().zip(&r).map(|(a, b)| a * b).collect::<Vec<_>>());
        let mut ssim = 0.0;
        for i in 0..n * n {
            let (st, sr) = (mt[i] - mt[i] * mt[i], mr[i] - mr[i] * mr[i]);
            let str_ = tr[i] - mt[i] * mr[i];
            ssim += (2.0 * mt[i] * mr[i] + c1) * (2.0 * str_ + c2)
                / ((mt[i] * mt[i] + mr[i] * mr[i] + c1) * (st + sr + c2));
        }
        total += ssim / (n * n) as f64;
    }
    total / 2.0
}

/// The challenge baseline's segmentation of an image sampled at the challenge's 256 x 256
/// pixels (`values`, None outside the tank): a three-class Otsu threshold over a 256-bin
/// histogram of the values inside; the largest class is water (0), the class below it
/// resistive (1), the one above it conductive (2).
#[must_use]
pub fn otsu_segmentation(values: &[Option<f64>]) -> Vec<u8> {
    let inside: Vec<f64> = values.iter().flatten().copied().collect();
    let (lo, hi) = inside
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    if inside.is_empty() || hi <= lo {
        return vec![0; values.len()];
    }
    let bins = 256;
    let bin = |v: f64| (((v - lo) / (hi - lo) * bins as f64) as usize).min(bins - 1);
    let mut hist = vec![0.0f64; bins];
    for v in &inside {
        hist[bin(*v)] += 1.0;
    }
    let centre = |b: usize| lo + (b as f64 + 0.5) * (hi - lo) / bins as f64;
    // Prefix sums of counts and first moments.
    let (mut w, mut m) = (vec![0.0; bins + 1], vec![0.0; bins + 1]);
    for b in 0..bins {
        w[b + 1] = w[b] + hist[b];
        m[b + 1] = m[b] + hist[b] * centre(b);
    }
    let class = |a: usize, b: usize| {
        let n = w[b] - w[a];
        if n > 0.0 {
            (m[b] - m[a]).powi(2) / n
        } else {
            0.0
        }
    };
    // Classes [0, t1), [t1, t2), [t2, bins): the largest between-class variance.
    let mut best = (f64::NEG_INFINITY, 1, 2);
    for t1 in 1..bins - 1 {
        for t2 in t1 + 1..bins {
            let score = class(0, t1) + class(t1, t2) + class(t2, bins);
            if score > best.0 {
                best = (score, t1, t2);
            }
        }
    }
    let (_, t1, t2) = best;
    let which = |v: f64| {
        let b = bin(v);
        usize::from(b >= t1) + usize::from(b >= t2)
    };
    let mut counts = [0usize; 3];
    for v in &inside {
        counts[which(*v)] += 1;
    }
    let water = (0..3).max_by_key(|&c| counts[c]).unwrap_or(1);
    values
        .iter()
        .map(|v| match v {
            None => 0,
            Some(v) => {
                let c = which(*v);
                match c.cmp(&water) {
                    std::cmp::Ordering::Equal => 0,
                    std::cmp::Ordering::Less => 1,
                    std::cmp::Ordering::Greater => 2,
                }
            }
        })
        .collect()
}
