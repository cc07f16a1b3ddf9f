//! The demo's second stage: the reference scenes imaged with every protocol, their metrics, and
//! the protocol the selector chooses.

use super::*;

/// The headline numbers of the imaging section.
pub(super) struct ImagingKey {
    /// (found within the touch radius, single-touch images).
    pub(super) single: (usize, usize),
    /// (found as exactly one touch, within its radius; single-touch images).
    pub(super) one_touch: (usize, usize),
    /// The same for the protocol docs/method.md §8 chooses from the AD image of each single touch.
    pub(super) chosen: (usize, usize),
    /// Protocols that found the two touches as two touches, each within its radius.
    pub(super) two: Vec<&'static str>,
}

/// One image of the section (`summary.json`'s "imaging"."images").
#[derive(Serialize)]
struct ImageRow {
    scene: &'static str,
    /// The protocol's name (`adjacent`, ...).
    protocol: &'static str,
    /// alpha chosen by GCV.
    alpha: f64,
    /// The ROI threshold f.
    threshold: f64,
    /// Touches counted (kept regions).
    regions: usize,
    /// For each true touch: the distance to the nearest counted touch, mm.
    touch_offsets_mm: Vec<f64>,
    /// For each true touch: whether that distance is within its radius.
    found_within_radius: Vec<bool>,
    /// docs/method.md §7's metrics of the image against its first touch.
    metrics: et_recon::metrics::Metrics,
    /// Each true touch matched to the nearest counted touch, with its own PE and SE.
    touch_matches: Vec<et_recon::TouchMatch>,
    /// The picture, relative to the report.
    png: String,
}

/// The protocol docs/method.md §8 chooses from one scene's adjacent image.
#[derive(Serialize)]
struct Decision {
    scene: &'static str,
    regions_on_adjacent: usize,
    /// None: no touch seen.
    #[serde(serialize_with = "protocol_name")]
    switch_to: Option<ProtocolKind>,
}

fn protocol_name<S: serde::Serializer>(
    k: &Option<ProtocolKind>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    k.map(ProtocolKind::name).serialize(s)
}

/// `summary.json`'s "imaging".
#[derive(Serialize)]
struct ImagingSummary<'a> {
    triangles: usize,
    single_touches_found: (usize, usize),
    single_touches_found_as_one_touch: (usize, usize),
    single_touches_found_with_chosen_protocol: (usize, usize),
    two_touches_found_by: &'a [&'static str],
    images: &'a [ImageRow],
    /// The protocol chosen for each scene from its adjacent image (docs/method.md §8; the
    /// key was "dynamic").
    protocol_choices: &'a [Decision],
}

/// Short names for the protocols, as the report shows them.
pub(super) fn short(kind: ProtocolKind) -> &'static str {
    match kind {
        ProtocolKind::Adjacent => "AD",
        ProtocolKind::PseudoPolar => "PP",
        ProtocolKind::PpPp => "PP-PP",
        ProtocolKind::Opposite => "opposite",
        ProtocolKind::Custom(_) => "custom",
    }
}

pub(super) fn imaging(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Section<ImagingKey>> {
    let scenes: Vec<(&'static str, Scene)> = REFERENCE_SCENES
        .iter()
        .map(|&s| Ok((s.0.trim_end_matches(".toml"), load(s)?)))
        .collect::<Result<_>>()?;
    let sheet_spec = &scenes[0].1.sheet;
    if scenes.iter().any(|(_, s)| &s.sheet != sheet_spec) {
        return Err(DemoError::Scenes(
            "the reference scenes differ in their sheet",
        ));
    }
    let bar = steps.bar(
        1 + ProtocolKind::NAMED.len() * (1 + scenes.len()),
        "imaging docs/method.md §7 scenes",
    );
    let base = scenes[0].1.scan_config()?;
    let adjacent = ScanConfig {
        protocol: ProtocolKind::Adjacent,
        ..base
    };
    // One reconstructor for the sheet: one-step Gauss-Newton with NOSER (s = 0.5), alpha by
    // generalised cross-validation on each frame, no closer than its noise, as
    // `et reconstruct`; a Jacobian and data space per protocol, shared by every scene.
    let mut recon = et_recon::Spec {
        mesh: et_recon::MeshPlan::About {
            triangles: sizes.triangles,
            refine: Vec::new(),
        },
        ..et_recon::Spec::new(sheet_spec.physical.clone(), adjacent.schedule()?)
    }
    .set_up()?;
    let sheet = simulated_sheet(&scenes[0].1)?;
    bar.inc(1);
    // docs/method.md §8's d_c: from the sheet's centre to its outline (where the electrodes are).
    let b = sheet_spec.physical.shape.bounds();
    let centre = [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])];
    let settings = Settings::new(
        centre,
        sheet_spec.physical.shape.distance_to_outline(centre),
    );
    let mut tally = Tally::default();
    for kind in ProtocolKind::NAMED {
        let config = ScanConfig {
            protocol: kind,
            ..base
        };
        recon.set_schedule(config.schedule()?)?;
        bar.inc(1);
        for (name, scene) in &scenes {
            let frames = scene_frames_on(&sheet, scene, &config, 10)?;
            let reference = et_recon::Reference {
                v0: frames.v0.clone(),
                var_dv: frames.var.clone(),
            };
            let shot = recon.image(&frames.v1, &reference)?;
            tally.add((*name, kind), &frames, shot, &settings, &recon);
            bar.inc(1);
        }
    }
    // One colour scale per scene (a row of the report's table): its protocols' largest change.
    let pictures = &tally.pictures;
    for (scene, png, title, marks, image) in pictures {
        let row = pictures
            .iter()
            .filter(|p| p.0 == *scene)
            .filter_map(|p| p.3.half_range)
            .fold(0.0, f64::max);
        let marks = plot::SheetMarks {
            half_range: Some(row),
            ..marks.clone()
        };
        plot::sheet_image(recon.imager(), &out.join(png), title, image, &marks)?;
    }
    steps.done(&bar, "imaged 5 scenes x 4 protocols");
    let Tally {
        rows,
        single,
        one_touch,
        two,
        decisions,
        ..
    } = tally;
    // Each single touch, imaged with the protocol docs/method.md §8 chose for it.
    let mut chosen = (0, 0);
    for d in &decisions {
        let found = rows.iter().find(|r| {
            r.scene == d.scene
                && d.switch_to.is_some_and(|k| r.protocol == k.name())
                && r.found_within_radius.len() == 1
        });
        if let Some(r) = found {
            chosen.1 += 1;
            chosen.0 += usize::from(r.found_within_radius[0]);
        }
    }
    let names: Vec<&str> = scenes.iter().map(|(name, _)| *name).collect();
    let md = markdown(recon.imager().triangles(), &names, &rows, &decisions);
    let json = serde_json::to_value(ImagingSummary {
        triangles: recon.imager().triangles(),
        single_touches_found: single,
        single_touches_found_as_one_touch: one_touch,
        single_touches_found_with_chosen_protocol: chosen,
        two_touches_found_by: &two,
        images: &rows,
        protocol_choices: &decisions,
    })?;
    Ok(Section {
        markdown: md,
        json,
        key: ImagingKey {
            single,
            one_touch,
            chosen,
            two,
        },
    })
}

/// A picture to draw once every protocol has imaged its scene: (scene, file, title, marks,
/// image).
type Picture = (
    &'static str,
    String,
    String,
    plot::SheetMarks,
    Vec<Option<f64>>,
);

/// The section's images so far and what they add up to.
#[derive(Default)]
struct Tally {
    rows: Vec<ImageRow>,
    /// (found within the touch radius, single-touch images).
    single: (usize, usize),
    /// (found as exactly one touch within its radius, single-touch images).
    one_touch: (usize, usize),
    /// Protocols that found two touches as two, each within its radius.
    two: Vec<&'static str>,
    decisions: Vec<Decision>,
    pictures: Vec<Picture>,
}

impl Tally {
    /// Scene `name` imaged with protocol `kind` (`shot`, of `frames`): its touches counted by
    /// docs/method.md §8's significance (`settings`), matched to the truth, its metrics, its
    /// picture, and on the adjacent protocol the selector's decision.
    fn add(
        &mut self,
        (name, kind): (&'static str, ProtocolKind),
        frames: &et_sim::still::SceneFrames,
        shot: et_recon::Image,
        settings: &Settings,
        recon: &et_recon::Reconstructor,
    ) {
        let f = shot.threshold;
        let (alpha, image, rois, dv) = (shot.alpha, shot.pixels, shot.regions, shot.dv);
        // Touches: the regions split at their saddles, standing out of the noise (estimated
        // from the reference frames), then docs/method.md §8's significance.
        let counted = significant(&shot.touches, settings);
        let png = format!("imaging/{name}-{}.png", kind.name());
        self.pictures.push((
            name,
            png.clone(),
            format!(
                "{name}, {}: {} found (f = {f})",
                short(kind),
                plot::touches(counted.len())
            ),
            plot::SheetMarks {
                truth: frames.truth.clone(),
                found: counted.iter().map(|g| g.centroid).collect(),
                roi: rois.iter().flat_map(|g| g.pixels.iter().copied()).collect(),
                half_range: Some(plot::half_range(recon.imager(), &image)),
            },
            image.clone(),
        ));
        // Each touch: the nearest counted touch (its own PE and SE), and whether its centroid
        // lies within the touch's radius.
        let touch_matches = et_recon::match_touches(recon.grid(), &counted, &frames.truth);
        let per_touch: Vec<(f64, bool)> = touch_matches
            .iter()
            .zip(&frames.truth)
            .map(|(m, &(c, r))| {
                let off = m.found.map_or(f64::INFINITY, |i| {
                    let g = counted[i].centroid;
                    (g[0] - c[0]).hypot(g[1] - c[1])
                });
                (off, off < r)
            })
            .collect();
        let (c, r) = frames.truth[0];
        let m = metrics(
            recon.grid(),
            &image,
            f,
            &dv,
            c,
            std::f64::consts::PI * r * r,
        );
        if frames.truth.len() == 1 {
            self.single.1 += 1;
            // The strongest region is the detection (docs/method.md §7's PE).
            let found = rois
                .first()
                .is_some_and(|g| (g.centroid[0] - c[0]).hypot(g.centroid[1] - c[1]) < r);
            self.single.0 += usize::from(found);
            self.one_touch.1 += 1;
            self.one_touch.0 += usize::from(counted.len() == 1 && per_touch[0].1);
        } else if counted.len() == frames.truth.len() && per_touch.iter().all(|t| t.1) {
            self.two.push(short(kind));
        }
        if kind == ProtocolKind::Adjacent {
            self.decisions.push(Decision {
                scene: name,
                regions_on_adjacent: counted.len(),
                switch_to: et_recon::select::decide(&counted, settings),
            });
        }
        self.rows.push(ImageRow {
            scene: name,
            protocol: kind.name(),
            alpha,
            threshold: f,
            regions: counted.len(),
            touch_offsets_mm: per_touch.iter().map(|t| t.0 * 1e3).collect(),
            found_within_radius: per_touch.iter().map(|t| t.1).collect(),
            metrics: m,
            touch_matches,
            png,
        });
    }
}

/// The section's report: the images, the table of their metrics and the protocol choices.
fn markdown(
    triangles: usize,
    scenes: &[&str],
    rows: &[ImageRow],
    decisions: &[Decision],
) -> String {
    let mut md = String::from("## 2. Imaging the reference scenarios (docs/method.md §7)\n\n");
    let _ = writeln!(
        md,
        "22 cm disc, 16 electrodes, targets of 1.46 % of the area at about 20 kPa. Frames: the \
         simulator's noisy frames (V_0 the mean of 10 untouched frames). Imaging: {} triangles, \
         complete electrode model, one-step Gauss-Newton with NOSER (s = 0.5, docs/method.md §6 [3.8-3.9]), \
         alpha by generalised cross-validation per frame, ROI threshold f per protocol as the \
         reference study (0.10 AD and opposite, 0.08 PP, 0.05 PP-PP). Colour: conductivity \
         change over the background. Touches: the regions of interest split at their saddles \
         (a peak stands apart when the dip below it is a quarter of the image's maximum, \
         `et_recon::touches`), kept when they reach 5 times their pixels' noise (the reference \
         frames' spread and the model's own error through the reconstruction matrix, \
         `et_recon::touch_rule`, the rule `et reconstruct` and `et stream` share), and when \
         their peak reaches half the strongest's and their area a quarter of a 10 mm fingertip's (`et_recon::select::significant`). The \"touches\" columns \
         count these touches.\n",
        triangles
    );
    images_table(&mut md, scenes);
    let _ = writeln!(
        md,
        "\nHow to read these images: colour is the conductivity change over the untouched \
         sheet's (red: more conductive, where pressed; blue: less; white: no change). Each row \
         (scene) shares one colour scale, symmetric about zero and set by the row's largest \
         change, so the four protocols compare by colour. Green circle: the true touch; black \
         cross numbered 1, 2: the touches found (1 the strongest); black outline: the ROI, the \
         pixels at or above f times the image's maximum, on which PE and SE are measured. Grey \
         is outside the sheet."
    );
    let _ = writeln!(
        md,
        "\n| scene | protocol | alpha | touches | distance of each true touch from the nearest found | PE | SE | RNG | BVC |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for r in rows {
        let offsets: Vec<String> = r
            .touch_offsets_mm
            .iter()
            .zip(&r.found_within_radius)
            .map(|(o, &within)| {
                format!(
                    "{o:.1} mm{}",
                    if within { " (within)" } else { " (outside)" }
                )
            })
            .collect();
        let m = &r.metrics;
        // Several touches: each one's PE and SE against the nearest found touch.
        let each = |f: fn(&et_recon::TouchMatch) -> f64, single: f64| {
            if r.touch_matches.len() > 1 {
                let v: Vec<String> = r
                    .touch_matches
                    .iter()
                    .map(|t| format!("{:.3}", f(t)))
                    .collect();
                v.join(", ")
            } else {
                format!("{single:.3}")
            }
        };
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {} | {} | {} | {} | {:.3} | {:.2e} V |",
            r.scene,
            r.protocol,
            r.alpha,
            r.regions,
            offsets.join(", "),
            each(|t| t.pe, m.pe),
            each(|t| t.se, m.se),
            m.rng,
            m.bvc,
        );
    }
    let _ = writeln!(
        md,
        "\nHow to read the table: *alpha* is the regularisation weight (larger: smoother, \
         less noisy images), picked by generalised cross-validation (GCV) on each frame. The \
         metrics are docs/method.md §7's: *PE*, position error, the \
         distance from the true centre to the centroid of the region of interest (ROI: the \
         pixels above f times the image's maximum) over the sheet's largest extent; *SE*, \
         size error, the difference between the ROI's area and the touch's over the sheet's \
         area (SE counts every region above the threshold); with two touches, PE and SE are \
         given for each, against the nearest counted touch's centroid and area \
         (`recon::match_touches`); *RNG*, ringing, the area of \
         opposite-sign change over the area outside the ROI (all three: 0 is best); *BVC*, \
         the boundary voltage change |V_m - V_0| the touch makes (larger: easier to see).\n\n\
         **Dynamic protocol selection (docs/method.md §8)** on the AD image of each scene (xi = 0.5):\n\n\
         | scene | touches on AD | docs/method.md §8 switches to |\n| --- | --- | --- |"
    );
    for d in decisions {
        let _ = writeln!(
            md,
            "| {} | {} | {} |",
            d.scene,
            d.regions_on_adjacent,
            match d.switch_to {
                None => "no touch seen".to_string(),
                Some(ProtocolKind::Adjacent) => "stays on AD".to_string(),
                Some(k) => short(k).to_string(),
            }
        );
    }
    md.push('\n');
    md
}

/// The table of the images: a row per scene, a column per protocol.
fn images_table(md: &mut String, scenes: &[&str]) {
    let _ = write!(md, "| scene |");
    for kind in ProtocolKind::NAMED {
        let _ = write!(md, " {} |", short(kind));
    }
    let _ = writeln!(md, "\n| --- | --- | --- | --- | --- |");
    for name in scenes {
        let _ = write!(md, "| {name} |");
        for kind in ProtocolKind::NAMED {
            let _ = write!(
                md,
                " ![{name} {}](imaging/{name}-{}.png) |",
                short(kind),
                kind.name()
            );
        }
        let _ = writeln!(md);
    }
}
