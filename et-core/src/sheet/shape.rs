//! Sheet outlines (docs/method.md §1): disc, rectangle, any simple polygon. Lengths in metres, the
//! origin at the sheet's centre for the disc and rectangle.

use serde::{Deserialize, Serialize};

/// The outline of a flat (or developable) sheet.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Shape {
    /// A disc of this radius, centred on the origin.
    Disc {
        /// Radius in m.
        radius: f64,
    },
    /// A rectangle centred on the origin.
    Rectangle {
        /// Extent along x in m.
        width: f64,
        /// Extent along y in m.
        height: f64,
    },
    /// A simple polygon, vertices counter-clockwise (m).
    Polygon {
        /// Vertices `[x, y]` in m (a last one repeating the first, as closed outlines list
        /// them, is read as the outline's closing).
        #[serde(deserialize_with = "outline")]
        vertices: Vec<[f64; 2]>,
    },
}

/// A polygon's vertices as a file lists them: a last vertex equal to the first (a closed
/// ring, as GIS files and shapely's `exterior.coords` write it) closes the outline and is not
/// a vertex of its own (it was refused as edges that touch).
fn outline<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    let mut vertices = super::xy::many(d)?;
    if vertices.len() > 3 && vertices.first() == vertices.last() {
        vertices.pop();
    }
    Ok(vertices)
}

/// Why a shape is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ShapeError {
    /// A size is not finite and positive.
    #[error("{field} = {value}: must be a positive length in metres")]
    Size {
        /// Which field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A polygon needs at least 3 vertices (at most [`MAX_VERTICES`]), all finite, and a
    /// non-zero area.
    #[error("polygon: {0}")]
    Polygon(&'static str),
    /// Two consecutive vertices at one point (0-based: `vertex` and the one after it).
    #[error(
        "polygon: vertices {vertex} and {} are the same point: list each corner once",
        .vertex + 1
    )]
    Repeated {
        /// The first of the two.
        vertex: usize,
    },
    /// An outline too narrow against its longer side to mesh.
    #[error(
        "the outline is a sliver: its area is {slenderness:.1e} of its longer side squared, \
         at least 1e-3 is meshed (a strip 1 m x 5 mm passes)"
    )]
    Sliver {
        /// Area over the square of the bounding box's longer side.
        slenderness: f64,
    },
    /// An outline wider than [`MAX_SPAN_M`]: lengths given in millimetres or centimetres.
    #[error(
        "the outline is {span:.1} m across, past the {max} m et takes: a scene's lengths are \
         in metres (a 28 cm tank's radius is 0.14): were they given in mm or cm?",
        max = MAX_SPAN_M
    )]
    Span {
        /// The bounding box's longer side, m.
        span: f64,
    },
}

/// The most vertices an outline may have: the mesher's cost grows with them (3 000 took 43 s,
/// 10 000 hung), and a sheet's outline needs far fewer (a disc is meshed from 24 to 200).
pub const MAX_VERTICES: usize = 1_000;

/// The widest an outline may be across (its bounding box's longer side, m). The frames
/// and images of a sheet do not change with its scale, so lengths given in millimetres image
/// a sheet a thousand times too large without a word (a 28 cm tank's radius of 140 put its
/// touch at (44 741, 36 743) mm); no skin, garment or tank is near 10 m across.
pub const MAX_SPAN_M: f64 = 10.0;

/// The narrowest an outline may be against its longest side (area over the square of the
/// bounding box's longer side): a strip 1 m x 5 mm passes (0.005), a 0.2 m x 1 um sliver
/// (5e-6) would ask the mesher for millions of triangles or none.
pub const MIN_SLENDERNESS: f64 = 1e-3;

impl Shape {
    /// Checks sizes and polygon sanity.
    ///
    /// # Errors
    /// [`ShapeError`] naming the bad field.
    pub fn validate(&self) -> Result<(), ShapeError> {
        let positive = |field, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ShapeError::Size { field, value })
            }
        };
        match self {
            Shape::Disc { radius } => {
                positive("radius", *radius)?;
                self.not_too_wide()
            }
            Shape::Rectangle { width, height } => {
                positive("width", *width)?;
                positive("height", *height)?;
                self.not_too_wide()?;
                self.not_a_sliver()
            }
            Shape::Polygon { vertices } => {
                if vertices.len() < 3 {
                    return Err(ShapeError::Polygon("needs at least 3 vertices"));
                }
                if vertices.len() > MAX_VERTICES {
                    return Err(ShapeError::Polygon(
                        "more than 1 000 vertices (the mesher's time grows with them; a \
                         sheet's outline needs far fewer: simplify it)",
                    ));
                }
                if vertices.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(ShapeError::Polygon("a vertex is not finite"));
                }
                if let Some(vertex) =
                    (0..vertices.len() - 1).find(|&i| vertices[i] == vertices[i + 1])
                {
                    return Err(ShapeError::Repeated { vertex });
                }
                // A bow-tie's halves cancel to zero area: it is said as crossing (it was said
                // as "zero area"), vertices on one line as what they are.
                if on_one_line(vertices) {
                    return Err(ShapeError::Polygon(
                        "zero area: the vertices lie on one line",
                    ));
                }
                if !is_simple(vertices) {
                    return Err(ShapeError::Polygon(
                        "edges cross or touch (the outline must be a simple polygon)",
                    ));
                }
                if self.signed_area().abs() < 1e-12 {
                    return Err(ShapeError::Polygon(
                        "zero area (below 1e-12 m^2: lengths are in metres)",
                    ));
                }
                if self.signed_area() < 0.0 {
                    // Walked clockwise, the outline would place and number the electrodes
                    // the other way round without a word (a mirrored image).
                    return Err(ShapeError::Polygon(
                        "vertices clockwise: give them counter-clockwise (the list reversed); \
                         electrodes.direction = \"cw\" numbers the electrodes clockwise",
                    ));
                }
                self.not_too_wide()?;
                self.not_a_sliver()
            }
        }
    }

    /// [`ShapeError::Span`] for an outline wider than [`MAX_SPAN_M`].
    fn not_too_wide(&self) -> Result<(), ShapeError> {
        let [x0, y0, x1, y1] = self.bounds();
        let span = (x1 - x0).max(y1 - y0);
        if span <= MAX_SPAN_M {
            Ok(())
        } else {
            Err(ShapeError::Span { span })
        }
    }

    /// [`ShapeError::Sliver`] for an outline narrower than [`MIN_SLENDERNESS`] of its longer
    /// side.
    fn not_a_sliver(&self) -> Result<(), ShapeError> {
        let [x0, y0, x1, y1] = self.bounds();
        let longest = (x1 - x0).max(y1 - y0);
        let slenderness = self.area() / (longest * longest);
        if slenderness >= MIN_SLENDERNESS {
            Ok(())
        } else {
            Err(ShapeError::Sliver { slenderness })
        }
    }

    fn signed_area(&self) -> f64 {
        match self {
            Shape::Polygon { vertices } => {
                let n = vertices.len();
                (0..n)
                    .map(|i| {
                        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                        a[0] * b[1] - b[0] * a[1]
                    })
                    .sum::<f64>()
                    / 2.0
            }
            _ => self.area(),
        }
    }

    /// Area in m^2.
    #[must_use]
    pub fn area(&self) -> f64 {
        match self {
            Shape::Disc { radius } => std::f64::consts::PI * radius * radius,
            Shape::Rectangle { width, height } => width * height,
            Shape::Polygon { .. } => self.signed_area().abs(),
        }
    }

    /// Axis-aligned bounding box `[x_min, y_min, x_max, y_max]`.
    #[must_use]
    pub fn bounds(&self) -> [f64; 4] {
        match self {
            Shape::Disc { radius } => [-radius, -radius, *radius, *radius],
            Shape::Rectangle { width, height } => {
                [-width / 2.0, -height / 2.0, width / 2.0, height / 2.0]
            }
            Shape::Polygon { vertices } => vertices.iter().fold(
                [
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ],
                |b, v| {
                    [
                        b[0].min(v[0]),
                        b[1].min(v[1]),
                        b[2].max(v[0]),
                        b[3].max(v[1]),
                    ]
                },
            ),
        }
    }

    /// The smaller side of the bounding box: the length scale that sets the resolution.
    #[must_use]
    pub fn size(&self) -> f64 {
        let b = self.bounds();
        (b[2] - b[0]).min(b[3] - b[1])
    }

    /// Whether `p` is inside or on the outline (within `tol` metres).
    #[must_use]
    pub fn contains(&self, p: [f64; 2], tol: f64) -> bool {
        match self {
            Shape::Disc { radius } => p[0].hypot(p[1]) <= radius + tol,
            Shape::Rectangle { width, height } => {
                p[0].abs() <= width / 2.0 + tol && p[1].abs() <= height / 2.0 + tol
            }
            Shape::Polygon { vertices } => {
                let n = vertices.len();
                let mut inside = false;
                for i in 0..n {
                    let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                    if segment_distance(p, a, b) <= tol {
                        return true;
                    }
                    if (a[1] > p[1]) != (b[1] > p[1]) {
                        let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                        if p[0] < x {
                            inside = !inside;
                        }
                    }
                }
                inside
            }
        }
    }

    /// Perimeter length in m.
    #[must_use]
    pub fn perimeter(&self) -> f64 {
        match self {
            Shape::Disc { radius } => 2.0 * std::f64::consts::PI * radius,
            _ => {
                let v = self.corners();
                (0..v.len()).map(|i| dist(v[i], v[(i + 1) % v.len()])).sum()
            }
        }
    }

    /// The outline's corners, counter-clockwise (none for the disc).
    #[must_use]
    pub fn corners(&self) -> Vec<[f64; 2]> {
        match self {
            Shape::Disc { .. } => Vec::new(),
            Shape::Rectangle { width, height } => {
                let (w, h) = (width / 2.0, height / 2.0);
                // Start at the middle of the bottom edge's left end so that electrode 0 sits
                // on an edge, not a corner, for the usual counts.
                vec![[-w, -h], [w, -h], [w, h], [-w, h]]
            }
            Shape::Polygon { vertices } => vertices.clone(),
        }
    }

    /// The point at arc-length fraction `t` (wrapping, 0..1) of the perimeter, walking
    /// counter-clockwise. For the disc, t = 0 is at angle 0 (+x); for polygons and rectangles,
    /// at the first vertex (the rectangle's lower-left corner).
    #[must_use]
    pub fn boundary_point(&self, t: f64) -> [f64; 2] {
        let t = t.rem_euclid(1.0);
        match self {
            Shape::Disc { radius } => {
                let a = 2.0 * std::f64::consts::PI * t;
                [radius * a.cos(), radius * a.sin()]
            }
            _ => {
                let v = self.corners();
                let mut s = t * self.perimeter();
                for i in 0..v.len() {
                    let (a, b) = (v[i], v[(i + 1) % v.len()]);
                    let l = dist(a, b);
                    if s <= l || i + 1 == v.len() {
                        let f = (s / l).clamp(0.0, 1.0);
                        return [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
                    }
                    s -= l;
                }
                v[0]
            }
        }
    }
}

impl Shape {
    /// Distance from `p` to the outline, m (whether `p` is inside or outside).
    #[must_use]
    pub fn distance_to_outline(&self, p: [f64; 2]) -> f64 {
        match self {
            Shape::Disc { radius } => (p[0].hypot(p[1]) - radius).abs(),
            _ => {
                let v = self.corners();
                (0..v.len())
                    .map(|i| segment_distance(p, v[i], v[(i + 1) % v.len()]))
                    .fold(f64::INFINITY, f64::min)
            }
        }
    }

    /// Arc-length fraction (0..1) of the outline point in the direction `deg` degrees
    /// (counter-clockwise from +x) from the outline's centre (the middle of its bounding
    /// box), for outlines that every such ray crosses once (discs, rectangles, convex
    /// polygons).
    #[must_use]
    pub fn arc_at_angle(&self, deg: f64) -> f64 {
        use std::f64::consts::{PI, TAU};
        let a = deg.to_radians();
        if let Shape::Disc { .. } = self {
            return (a / TAU).rem_euclid(1.0);
        }
        let b = self.bounds();
        let c = [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])];
        // The angle of the outline point at t, less `a`, wrapped to [-pi, pi).
        let off = |t: f64| {
            let p = self.boundary_point(t);
            ((p[1] - c[1]).atan2(p[0] - c[0]) - a + PI).rem_euclid(TAU) - PI
        };
        let n = 3_600;
        let coarse = (0..n)
            .map(|i| f64::from(i) / f64::from(n))
            .min_by(|&s, &t| off(s).abs().total_cmp(&off(t).abs()))
            .unwrap_or(0.0);
        // The angle grows with t (counter-clockwise): bisect the sign change around it.
        let (mut lo, mut hi) = (coarse - 1.0 / f64::from(n), coarse + 1.0 / f64::from(n));
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if off(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0.5 * (lo + hi)).rem_euclid(1.0)
    }

    /// Arc-length fraction (0..1) of the outline point nearest to `p`: the inverse of
    /// [`Shape::boundary_point`].
    #[must_use]
    pub fn arc_of(&self, p: [f64; 2]) -> f64 {
        match self {
            Shape::Disc { .. } => (p[1].atan2(p[0]) / (2.0 * std::f64::consts::PI)).rem_euclid(1.0),
            _ => {
                let v = self.corners();
                let total = self.perimeter();
                let (mut best, mut best_d, mut walked) = (0.0, f64::INFINITY, 0.0);
                for i in 0..v.len() {
                    let (a, b) = (v[i], v[(i + 1) % v.len()]);
                    let l = dist(a, b);
                    let t = if l > 0.0 {
                        (((p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1])) / (l * l))
                            .clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let d = dist(p, [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
                    if d < best_d {
                        best_d = d;
                        best = (walked + t * l) / total;
                    }
                    walked += l;
                }
                best.rem_euclid(1.0)
            }
        }
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// Whether every vertex of `v` (at least two, the first two apart) lies on the line through
/// the first two, to rounding.
fn on_one_line(v: &[[f64; 2]]) -> bool {
    let [x0, y0] = v[0];
    let (dx, dy) = (v[1][0] - x0, v[1][1] - y0);
    v.iter().all(|&[x, y]| {
        let (ex, ey) = (x - x0, y - y0);
        (dx * ey - dy * ex).abs() <= 1e-9 * dx.hypot(dy) * ex.hypot(ey)
    })
}

/// Whether the closed polyline `v` is a simple polygon: no two edges meet except neighbours at
/// their shared vertex (so no crossing, no touching, no repeated vertex). O(n^2): outlines have
/// tens of vertices.
fn is_simple(v: &[[f64; 2]]) -> bool {
    let n = v.len();
    let edge = |i: usize| (v[i], v[(i + 1) % n]);
    (0..n).all(|i| {
        (i + 1..n).all(|j| {
            let neighbours = j == i + 1 || (i == 0 && j == n - 1);
            let (a, b) = edge(i);
            let (c, d) = edge(j);
            if neighbours {
                // Neighbours share one vertex; they must not fold back onto each other.
                let (shared, p, q) = if j == i + 1 { (b, a, d) } else { (a, b, c) };
                !(orient(p, shared, q) == 0.0 && dot(p, shared, q) > 0.0)
            } else {
                !segments_meet(a, b, c, d)
            }
        })
    })
}

/// Twice the signed area of the triangle (a, b, c).
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// (p - o) . (q - o): positive when p and q lie on the same side of o.
fn dot(p: [f64; 2], o: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - o[0]) * (q[0] - o[0]) + (p[1] - o[1]) * (q[1] - o[1])
}

/// Whether the closed segments ab and cd share a point.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on(c, d, a))
        || (d2 == 0.0 && on(c, d, b))
        || (d3 == 0.0 && on(a, b, c))
        || (d4 == 0.0 && on(a, b, d))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Outlines the mesher cannot take are refused: a bow tie (edges cross; its signed area
    /// is 0 only when symmetric, so an asymmetric one passed the area check and panicked the
    /// mesher), a figure eight touching at a vertex, a spike folding back on its edge. Simple
    /// outlines, convex or not, pass.
    #[test]
    fn only_simple_polygons_are_outlines() {
        let poly = |v: &[[f64; 2]]| Shape::Polygon {
            vertices: v.to_vec(),
        };
        for (shape, what) in [
            (
                poly(&[[0.0, 0.0], [0.1, 0.1], [0.1, 0.0], [0.0, 0.12]]),
                "bow tie",
            ),
            (
                poly(&[
                    [0.0, 0.0],
                    [0.1, 0.0],
                    [0.05, 0.05],
                    [0.1, 0.1],
                    [0.0, 0.1],
                    [0.05, 0.05],
                ]),
                "figure eight",
            ),
            (
                poly(&[[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.1, 0.05], [0.0, 0.1]]),
                "spike back along an edge",
            ),
        ] {
            assert!(shape.signed_area().abs() >= 1e-12, "{what}: area");
            assert!(
                matches!(shape.validate(), Err(ShapeError::Polygon(_))),
                "{what}"
            );
        }
        let l_shape = poly(&[
            [0.0, 0.0],
            [0.1, 0.0],
            [0.1, 0.05],
            [0.05, 0.05],
            [0.05, 0.1],
            [0.0, 0.1],
        ]);
        l_shape.validate().unwrap();
        // A symmetric bow tie's halves cancel to zero area: said as crossing, not as "zero
        // area"; vertices on one line as that.
        let said = |shape: Shape| shape.validate().unwrap_err().to_string();
        let e = said(poly(&[[0.0, 0.0], [0.1, 0.1], [0.1, 0.0], [0.0, 0.1]]));
        assert!(e.contains("edges cross"), "{e}");
        let e = said(poly(&[[0.0, 0.0], [0.1, 0.0], [0.3, 0.0]]));
        assert!(e.contains("zero area: the vertices lie on one line"), "{e}");
    }

    /// An outline past 10 m across is a scene's lengths in mm or cm (the frames do not show
    /// the scale): each kind is refused saying so; one just inside passes.
    #[test]
    fn an_outline_in_millimetres_is_refused() {
        let in_mm = [
            Shape::Disc { radius: 140.0 },
            Shape::Rectangle {
                width: 130.0,
                height: 130.0,
            },
            Shape::Polygon {
                vertices: vec![[0.0, 0.0], [300.0, 0.0], [0.0, 200.0]],
            },
        ];
        for (shape, span) in in_mm.iter().zip([280.0, 130.0, 300.0]) {
            let e = shape.validate().unwrap_err();
            assert_eq!(e, ShapeError::Span { span }, "{shape:?}");
            assert!(
                e.to_string().contains("were they given in mm or cm?"),
                "{e}"
            );
        }
        Shape::Disc {
            radius: MAX_SPAN_M / 2.0,
        }
        .validate()
        .unwrap();
        let over = Shape::Disc {
            radius: MAX_SPAN_M / 2.0 * (1.0 + 1e-9),
        };
        assert!(matches!(over.validate(), Err(ShapeError::Span { .. })));
    }

    /// A closed ring (its first vertex repeated last, as shapely's `exterior.coords` and GIS
    /// files list it) is the same outline; a corner listed twice in a row is said by its
    /// place (both were "edges cross or touch").
    #[test]
    fn a_closed_ring_is_its_outline_and_a_repeated_corner_is_named() {
        let read = |vertices: &str| {
            let json = format!(r#"{{"kind": "polygon", "vertices": {vertices}}}"#);
            serde_json::from_str::<Shape>(&json).unwrap()
        };
        let open = read("[[0, 0], [0.1, 0], [0.1, 0.1], [0, 0.1]]");
        assert_eq!(
            read("[[0, 0], [0.1, 0], [0.1, 0.1], [0, 0.1], [0, 0]]"),
            open
        );
        open.validate().unwrap();
        let twice = read("[[0, 0], [0.1, 0], [0.1, 0], [0.1, 0.1], [0, 0.1]]");
        let e = twice.validate().unwrap_err().to_string();
        assert_eq!(
            e,
            "polygon: vertices 1 and 2 are the same point: list each corner once"
        );
    }

    #[test]
    fn containment_area_and_perimeter() {
        let square = Shape::Rectangle {
            width: 0.13,
            height: 0.13,
        };
        let poly = Shape::Polygon {
            vertices: vec![
                [-0.065, -0.065],
                [0.065, -0.065],
                [0.065, 0.065],
                [-0.065, 0.065],
            ],
        };
        for s in [&square, &poly] {
            s.validate().unwrap();
            assert!((s.area() - 0.0169).abs() < 1e-12);
            assert!((s.perimeter() - 0.52).abs() < 1e-12);
            assert!(s.contains([0.0, 0.0], 0.0) && s.contains([0.065, 0.0], 1e-12));
            assert!(!s.contains([0.07, 0.0], 1e-6));
            let p = s.boundary_point(0.125);
            assert!(
                (p[0] - 0.0).abs() < 1e-12 && (p[1] + 0.065).abs() < 1e-12,
                "{p:?}"
            );
        }
        for t in [0.0, 0.1, 0.37, 0.5, 0.93] {
            for s in [&square, &poly] {
                assert!((s.arc_of(s.boundary_point(t)) - t).abs() < 1e-12, "{t}");
            }
        }
        let disc = Shape::Disc { radius: 0.11 };
        assert!((disc.boundary_point(0.25)[1] - 0.11).abs() < 1e-12);
        assert!((disc.arc_of(disc.boundary_point(0.8)) - 0.8).abs() < 1e-12);
        assert!(disc.contains([0.0, 0.109], 0.0) && !disc.contains([0.08, 0.08], 0.0));
        // An L-shape: the notch is outside.
        let l = Shape::Polygon {
            vertices: vec![
                [0.0, 0.0],
                [2.0, 0.0],
                [2.0, 1.0],
                [1.0, 1.0],
                [1.0, 2.0],
                [0.0, 2.0],
            ],
        };
        assert!(l.contains([0.5, 1.5], 0.0) && !l.contains([1.5, 1.5], 0.0));
        assert!((l.area() - 3.0).abs() < 1e-12);
    }

    #[test]
    fn bad_shapes_name_the_field() {
        assert_eq!(
            Shape::Disc { radius: -1.0 }.validate(),
            Err(ShapeError::Size {
                field: "radius",
                value: -1.0
            })
        );
        assert!(matches!(
            Shape::Rectangle {
                width: 1.0,
                height: f64::NAN
            }
            .validate(),
            Err(ShapeError::Size {
                field: "height",
                ..
            })
        ));
        assert!(
            Shape::Polygon {
                vertices: vec![[0.0, 0.0], [1.0, 1.0]]
            }
            .validate()
            .is_err()
        );
        assert!(
            Shape::Polygon {
                vertices: vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]
            }
            .validate()
            .is_err()
        );
    }
}
