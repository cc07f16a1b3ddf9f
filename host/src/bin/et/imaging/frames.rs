//! Which frames `et reconstruct` images: simulated from the scene, read from a recording, or
//! another system's table of frames; one (`--frame`, default the last) or many (`--all`,
//! `--range`, each imaged here against the reference set once).

use std::ops::Range;
use std::path::Path;

use anyhow::{Context, Result, bail};
use et_host::recording;
use et_sim::scene::Scene;

use super::ReconstructArgs;

/// What `et reconstruct` images: V_0 and its noise, the frames chosen (their 0-based index in
/// the file and values, in order; one unless `--all` or `--range`), and the truth (centre,
/// radius) of the last where known.
pub(super) struct Chosen {
    pub(super) reference: et_recon::Reference,
    /// The frames V_0 was made of (`--reference N` or `--reference-file`; empty for the
    /// simulator's).
    pub(super) reference_frames: Vec<Vec<f32>>,
    pub(super) frames: Vec<(usize, Vec<f32>)>,
    pub(super) truth: Vec<et_sim::still::Truth>,
    /// The frames of `--all` or `--range` left out for values missing (0-based, ascending).
    pub(super) skipped: Vec<usize>,
}

/// The frames to image among `n`, of which those from `first` on may be imaged (the ones
/// before are the reference): `--all`, `--range`, or `--frame` (default the last).
fn chosen(args: &ReconstructArgs, path: &str, first: usize, n: usize) -> Result<Range<usize>> {
    let last = n.saturating_sub(1);
    let range = match (args.all, args.range, args.frame) {
        (true, _, _) => first..n,
        (_, Some(r), _) => {
            // Past the end: refused as --rows refuses it (it imaged fewer frames than asked,
            // without a word).
            if let Some(end) = r
                .end
                .filter(|&end| end > n && (first..n).contains(&r.start))
            {
                bail!(
                    "{path}: --range {r}: {n} frames (0 to {last}), so frame {} is not among \
                     them; write {}.. for every frame from {} to the end",
                    end - 1,
                    r.start,
                    r.start
                );
            }
            r.start..r.end.unwrap_or(n).min(n)
        }
        (_, None, frame) => {
            let frame = frame.unwrap_or(last);
            frame..frame + 1
        }
    };
    if n == 0 {
        bail!("{path}: no frames to image");
    }
    if n <= first || range.start < first || range.start >= n || range.is_empty() {
        let asked = match (args.all, args.range) {
            (true, _) => "--all".to_string(),
            (_, Some(r)) => format!("--range {r}"),
            _ => format!("--frame {}", range.start),
        };
        if n <= first {
            bail!(
                "{path}: {n} frames; the first {first} are the reference V_0 and none is left \
                 to image (lower --reference, or give --reference-file)"
            );
        }
        bail!(
            "{path}: {asked}: the frames to image are {first} to {last} ({})",
            match first {
                // (--reference-file gives V_0: every frame may be imaged.)
                0 => "frames count from 0; the reference V_0 is --reference-file's".to_string(),
                1 => "the frame before them is the reference V_0".to_string(),
                _ => format!("the {first} frames before them are the reference V_0"),
            }
        );
    }
    Ok(range)
}

/// `--reference`'s count of untouched frames at the start of a file of `n` frames: at least
/// one frame must be left to image after them. Said as the user gave it (the default too).
fn reference_count(args: &ReconstructArgs, path: &str, n: usize) -> Result<usize> {
    if n < 2 {
        bail!(
            "{path}: {}: at least one untouched frame (--reference) and one to image are \
             needed; give the untouched frames with --reference-file, or more frames",
            match n {
                0 => "no frames".to_string(),
                _ => "1 frame".to_string(),
            }
        );
    }
    if args.reference >= n {
        bail!(
            "{path}: {n} frame{}; --reference {} asks for {} untouched frames before the ones \
             to image (20 unless given): lower --reference (at most {}), or give the untouched \
             frames with --reference-file",
            if n == 1 { "" } else { "s" },
            args.reference,
            args.reference,
            n.saturating_sub(1)
        );
    }
    Ok(args.reference)
}

/// The frames `et reconstruct` images from the scene or an et recording.
pub(super) fn frames(
    args: &ReconstructArgs,
    scene: &Scene,
    recording: Option<&recording::Recording>,
    config: &et_core::ScanConfig,
) -> Result<Chosen> {
    let Some(r) = recording else {
        // The simulator's frames: the untouched sheet (mean of 10 frames, as captured at
        // set-up) and one frame with the scene's touches.
        let f = et_sim::still::scene_frames(scene, config, 10)?;
        let reference = et_recon::Reference {
            v0: f.v0,
            var_dv: f.var,
        };
        return Ok(Chosen {
            reference,
            reference_frames: Vec::new(),
            frames: vec![(0, f.v1)],
            truth: f.truth,
            skipped: Vec::new(),
        });
    };
    let path = args
        .frames
        .as_deref()
        .unwrap_or(std::path::Path::new(""))
        .display()
        .to_string();
    let n = r.records.len();
    // The untouched frames from --reference-file (it was ignored beside a recording), or the
    // recording's first --reference.
    let (given, reference) = match &args.reference_file {
        Some(f) => (Some(reference_file(f, r.header.frame_len)?), 0),
        None => (None, reference_count(args, &path, n)?),
    };
    let range = chosen(args, &path, reference, n)?;
    let (Some(before), Some(imaged)) = (r.records.get(..reference), r.records.get(range.clone()))
    else {
        bail!("{path}: {n} frames; need the reference frames 0..{reference} and later ones");
    };
    let gaps: Vec<usize> = (range.clone().zip(imaged))
        .filter(|(_, rec)| !rec.invalid.is_empty())
        .map(|(i, _)| i)
        .collect();
    let skipped = skip_gaps(args, &path, &gaps, range.len());
    if let Some((i, rec)) = before
        .iter()
        .enumerate()
        .chain((range.clone().zip(imaged)).filter(|(i, _)| !skipped.contains(i)))
        .find(|(_, rec)| !rec.invalid.is_empty())
    {
        bail!(
            "{path}: frame {i} (seq {}) has non-finite values (null in the file) in \
             columns {:?}; choose other frames with --reference and --frame or --range",
            rec.seq,
            rec.invalid
        );
    }
    // (Beside --reference-file, `before` is empty.)
    say_flagged(&path, before, imaged, "--reference, --frame, --range");
    let frames: Vec<&[f32]> = before.iter().map(|rec| rec.voltages.as_slice()).collect();
    let (reference, reference_frames) = match given {
        Some(given) => given,
        None => (
            et_recon::Reference::from_frames(&frames)?,
            frames.iter().map(|f| f.to_vec()).collect(),
        ),
    };
    let truth = imaged
        .last()
        .and_then(|rec| rec.touches.as_ref())
        .into_iter()
        .flatten()
        .map(|t| ([t.x, t.y], t.radius))
        .collect();
    Ok(Chosen {
        reference,
        reference_frames,
        frames: (range.zip(imaged))
            .filter(|(i, _)| !skipped.contains(i))
            .map(|(i, rec)| (i, rec.voltages.clone()))
            .collect(),
        truth,
        skipped,
    })
}

/// Says which of the frames used the board flagged (readings on an ADC rail, the current
/// source in compliance): `before` the reference frames, `imaged` those imaged, of the
/// recording `path`; `choose` the flags that choose others.
fn say_flagged(
    path: &str,
    before: &[recording::Record],
    imaged: &[recording::Record],
    choose: &str,
) {
    let flags = |recs: &[recording::Record]| recs.iter().fold(0u8, |f, rec| f | rec.flags);
    let count = |recs: &[recording::Record]| {
        let flagged = recs
            .iter()
            .filter(|rec| et_host::live::readings_flagged(rec.flags))
            .count();
        (flagged > 0).then(|| format!("{flagged} of the {} ", recs.len()))
    };
    let Some(words) = et_host::live::flagged_readings(flags(before) | flags(imaged)) else {
        return;
    };
    let which: Vec<String> = [
        count(before).map(|n| format!("{n}reference frames")),
        count(imaged).map(|n| format!("{n}imaged")),
    ]
    .into_iter()
    .flatten()
    .collect();
    say!(
        "warning: {path}: {words} in {}: their values may not be the sheet's, and images of \
         them place touches wrongly; choose frames it did not flag ({choose}) or fix what it \
         flags",
        which.join(" and ")
    );
}

/// The untouched frames of `--reference-file` (K values each), averaged, and as read:
/// another system's frames in any format `--frames` reads, or an et recording (every frame
/// of it; a recording was read as a CSV and refused for its JSON).
fn reference_file(path: &Path, k: usize) -> Result<(et_recon::Reference, Vec<Vec<f32>>)> {
    if et_host::frames::reads_as_table(path) {
        let r = et_host::frames::read(path, k)?;
        r.check_whole(path, 0..r.frames.len(), "another --reference-file")?;
        say!("reference {}", r.description);
        return Ok((et_recon::Reference::from_frames(&r.frames)?, r.frames));
    }
    let r = recording::read(path)?;
    for note in r.notes() {
        say!("note: {}: {note}", path.display());
    }
    if r.header.frame_len != k {
        bail!(
            "{}: frames of K = {} values, the frames imaged have K = {k}",
            path.display(),
            r.header.frame_len
        );
    }
    if let Some(rec) = r.records.iter().find(|rec| !rec.invalid.is_empty()) {
        bail!(
            "{}: frame seq {} has non-finite values (null in the file) in columns {:?}: \
             not an untouched reference",
            path.display(),
            rec.seq,
            rec.invalid
        );
    }
    let shown = path.display().to_string();
    say_flagged(&shown, &r.records, &[], "another --reference-file");
    let frames: Vec<&[f32]> = r
        .records
        .iter()
        .map(|rec| rec.voltages.as_slice())
        .collect();
    say!(
        "reference {}: {} frames of {k} values (an et recording)",
        path.display(),
        frames.len()
    );
    let reference = et_recon::Reference::from_frames(&frames)
        .with_context(|| format!("{}: the reference frames", path.display()))?;
    Ok((reference, frames.iter().map(|f| f.to_vec()).collect()))
}

/// Another system's frames from a table file: V_0 from `--reference-file` or the first
/// `--reference` frames, and the frames chosen. No truth is known.
pub(super) fn table_frames(
    args: &ReconstructArgs,
    path: &std::path::Path,
    k: usize,
) -> Result<Chosen> {
    let mut frames = et_host::frames::read(path, k)?;
    say!("{}", frames.description);
    let n = frames.frames.len();
    let mut reference_frames = Vec::new();
    let (reference, first) = match &args.reference_file {
        Some(f) => {
            let (reference, frames) = reference_file(f, k)?;
            reference_frames = frames;
            (reference, 0)
        }
        None => {
            let count = reference_count(args, &path.display().to_string(), n)?;
            frames.check_whole(path, 0..count, "--reference (frames 0 to N-1 are V_0)")?;
            let before = frames.frames.get(..count.min(n)).unwrap_or_default();
            // An empty reference is refused by `chosen` below with the reason; any other
            // fault of the frames is said (a value past single precision was said as a
            // reference of 0 values).
            let reference = if before.is_empty() {
                et_recon::Reference {
                    v0: Vec::new(),
                    var_dv: Vec::new(),
                }
            } else {
                reference_frames = before.to_vec();
                et_recon::Reference::from_frames(before)
                    .with_context(|| format!("{}: the reference frames", path.display()))?
            };
            (reference, count)
        }
    };
    let range = chosen(args, &path.display().to_string(), first, n)?;
    let gaps: Vec<usize> = (frames.gaps.iter().copied())
        .filter(|i| range.contains(i))
        .collect();
    let skipped = skip_gaps(args, &path.display().to_string(), &gaps, range.len());
    if skipped.is_empty() {
        frames.check_whole(path, range.clone(), "--frame or --range")?;
    }
    let imaged = frames.frames.drain(range.clone());
    Ok(Chosen {
        reference,
        reference_frames,
        frames: (range.zip(imaged))
            .filter(|(i, _)| !skipped.contains(i))
            .collect(),
        truth: Vec::new(),
        skipped,
    })
}

/// Of `--all` or `--range`'s `chosen` frames, those with values missing (`gaps`: a DAQ's
/// dropped sample, a recording's null) left out of the images and said: every other frame is
/// imaged (one such frame refused the whole file). None under `--frame`, which names one
/// frame, or where every frame chosen has values missing: those are refused by the frame.
fn skip_gaps(args: &ReconstructArgs, path: &str, gaps: &[usize], chosen: usize) -> Vec<usize> {
    if !(args.all || args.range.is_some()) || gaps.is_empty() || gaps.len() == chosen {
        return Vec::new();
    }
    let one = gaps.len() == 1;
    say!(
        "note: {path}: {} skipped, with values missing (empty or NaN cells, a recording's null: \
         values the system did not send): frame{} {} (from 0){}",
        if one {
            "1 frame".to_string()
        } else {
            format!("{} frames", gaps.len())
        },
        if one { "" } else { "s" },
        et_host::frames::said_list(gaps),
        match [&args.image_out, &args.segment].map(|p| p.as_ref().map(|p| p.display())) {
            [None, None] => String::new(),
            [a, b] => format!(
                "; {} in {} {} NaN, so that it keeps one image a frame",
                if one { "its image" } else { "their images" },
                [a, b]
                    .into_iter()
                    .flatten()
                    .map(|p| p.to_string())
                    .collect::<Vec<_>>()
                    .join(" and "),
                if one { "is" } else { "are" }
            ),
        }
    );
    gaps.to_vec()
}

/// The paths `et reconstruct` reads and writes checked before any work: no output replaces
/// an input, and none an existing file without `--force`.
pub(super) fn check_paths(args: &ReconstructArgs, scene: &Scene, force: bool) -> Result<()> {
    let named = scene.files();
    let mut inputs = vec![args.scene.as_path()];
    inputs.extend(named.iter().map(std::path::PathBuf::as_path));
    inputs.extend(args.frames.as_deref());
    inputs.extend(args.reference_file.as_deref());
    // `--mesh nodes.csv,triangles.csv,electrodes.csv` names inputs too.
    let mesh_files: Vec<&Path> = args
        .mesh
        .mesh
        .as_deref()
        .map(|m| m.split(',').map(|f| Path::new(f.trim())).collect())
        .unwrap_or_default();
    inputs.extend(mesh_files);
    let mut outputs: Vec<&Path> = args.out.as_deref().into_iter().collect();
    outputs.extend(args.image_out.as_deref());
    outputs.extend(args.segment.as_deref());
    crate::output::check_all(&outputs, &[], &inputs, force)?;
    if let Some(out) = &args.out {
        crate::output::check_format(out, "the image (PNG)", &["png"])?;
    }
    for npy in [&args.image_out, &args.segment].into_iter().flatten() {
        crate::output::check_format(npy, "a NumPy array", &["npy"])?;
    }
    Ok(())
}

/// Says (a warning on standard error) when frames to image are not alike their reference:
/// the first past [`et_recon::reconstructor::FRAME_SCALE_SAID`] times V_0 or under its
/// inverse, and how many are (a reference in mV against frames in V was imaged silently as
/// a press everywhere).
pub(super) fn say_unlike_frames(reference: &et_recon::Reference, chosen: &[(usize, Vec<f32>)]) {
    use et_recon::reconstructor::FRAME_SCALE_SAID;
    let unlike: Vec<(usize, f64)> = chosen
        .iter()
        .filter_map(|(i, v)| Some((*i, reference.scale_of(v)?)))
        .filter(|(_, s)| !(1.0 / FRAME_SCALE_SAID..=FRAME_SCALE_SAID).contains(s))
        .collect();
    if let Some((i, s)) = unlike.first() {
        say!(
            "warning: frame {i} is {} times the reference V_0 (the median of its values' \
             ratios; {} of {} frames past {FRAME_SCALE_SAID} times either way): {} A press \
             changes a frame by a few per cent",
            crate::tabular::significant(*s),
            unlike.len(),
            chosen.len(),
            unlike_why(*s)
        );
    }
}

/// What a frame `scale` times its reference asks: another unit or current, or where the
/// scale is negative, the other sign (it asked a reference of the other sign for units).
fn unlike_why(scale: f64) -> &'static str {
    if scale < 0.0 {
        "the other sign: were the frames' or the reference's measurement wires swapped, or \
         their current driven the other way?"
    } else {
        "are the frames and the reference in the same units, at the same current?"
    }
}

/// `schedule` and `chosen` without every value the electrodes `skip` (counted from `base`,
/// as the scene's user counts them) drive or measure (`--skip-electrodes`): a detached or
/// broken electrode's values left out. Says what is left out.
pub(super) fn skip_electrodes(
    skip: &[u16],
    base: u16,
    schedule: &mut et_core::schedule::Schedule,
    chosen: &mut Chosen,
) -> Result<()> {
    if skip.is_empty() {
        return Ok(());
    }
    let l = schedule.electrodes();
    let last = l - 1 + usize::from(base);
    let zero_based = (skip.iter())
        .map(
            |&e| match e.checked_sub(base).filter(|e| usize::from(*e) < l) {
                Some(e) => Ok(e),
                None => bail!(
                    "--skip-electrodes {e}: the scene's electrodes are {base} to {last}{}",
                    if base == 0 {
                        ""
                    } else {
                        " (its protocol file counts them from 1)"
                    }
                ),
            },
        )
        .collect::<Result<Vec<u16>>>()?;
    let k = schedule.frame_len();
    let (without, kept) =
        (schedule.without(&zero_based)).map_err(|e| anyhow::anyhow!("--skip-electrodes: {e}"))?;
    let keep = |v: &[f32]| kept.iter().map(|k| v[*k]).collect::<Vec<f32>>();
    let reference = &mut chosen.reference;
    reference.v0 = kept.iter().map(|k| reference.v0[*k]).collect();
    if reference.var_dv.len() == k {
        reference.var_dv = kept.iter().map(|k| reference.var_dv[*k]).collect();
    }
    for frame in &mut chosen.reference_frames {
        *frame = keep(frame);
    }
    for (_, frame) in &mut chosen.frames {
        *frame = keep(frame);
    }
    let named: Vec<String> = skip.iter().map(u16::to_string).collect();
    say!(
        "note: --skip-electrodes {}: {} of the frame's {k} values left out (every value they \
         drive or measure), {} imaged",
        named.join(","),
        k - kept.len(),
        kept.len()
    );
    *schedule = without;
    Ok(())
}

/// Warns of an electrode whose values stand out in the frames to image (`chosen`, each K
/// values) as a detached or broken electrode's, when V_0's did not name it (`in_reference`,
/// 0-based): a clip that came off during the recording ([`et_recon::Reconstructor::came_off`],
/// counted from `base`).
pub(super) fn say_detached_in_frames(
    recon: &et_recon::Reconstructor,
    base: u16,
    chosen: &[(usize, Vec<f32>)],
    in_reference: &[u16],
) {
    if let Some(off) = recon.came_off(chosen, in_reference) {
        let leave_out = |n| format!("--skip-electrodes {n} leaves them out");
        say!("warning: {}", off.said(base, leave_out));
    }
}
