//! Which sheet a simulated recording was made on, against the sheet it is imaged on.

use std::path::Path;

use et_core::sheet::{Shape, Sheet};

use super::Recording;

impl Recording {
    /// A note when this recording was simulated (`sim:<scene>`, as `et sim` writes its
    /// source) on a sheet of another outline, electrode width or electrode placement than
    /// `sheet`, the one it is about to be imaged on: the frames of a 22 cm disc imaged on the
    /// 13 cm square gave a picture of wrong touches, warned of only as a model that explains
    /// the untouched frame poorly. The sheet's and contacts' resistances are left out (the
    /// background fit takes them from the frames). `None` for any other source, or a scene
    /// that cannot be read where the recording says (moved, or named from another folder).
    #[must_use]
    pub fn made_on_another_sheet(&self, sheet: &Sheet) -> Option<String> {
        let path = self.header.source.strip_prefix("sim:")?;
        let made = et_sim::scene::Scene::load(Path::new(path))
            .ok()?
            .sheet
            .physical;
        let placed = |s: &Sheet| s.electrodes.centres(&s.shape);
        let same = made.shape == sheet.shape
            && made.electrodes.width == sheet.electrodes.width
            && placed(&made) == placed(sheet);
        (!same).then(|| {
            format!(
                "its frames were simulated on {path}'s sheet ({}), not on the sheet they are \
                 imaged on ({}): one sheet's frames imaged on another's outline or electrodes \
                 give touches where there were none; image them with --scene {path}",
                said(&made),
                said(sheet)
            )
        })
    }
}

/// A sheet as a person names it: "a disc of radius 110 mm, 16 electrodes 6 mm wide".
fn said(s: &Sheet) -> String {
    let outline = match &s.shape {
        Shape::Disc { radius } => format!("a disc of radius {} mm", mm(*radius)),
        Shape::Rectangle { width, height } => {
            format!("a {} x {} mm rectangle", mm(*width), mm(*height))
        }
        Shape::Polygon { vertices } => format!("a polygon of {} vertices", vertices.len()),
    };
    format!(
        "{outline}, {} electrodes {} mm wide",
        s.electrodes.count,
        mm(s.electrodes.width)
    )
}

/// A length in m as mm to a tenth (0.11 m is "110", not "110.00000000000001").
fn mm(m: f64) -> f64 {
    (m * 1e4).round() / 10.0
}
