//! The viewer driven headless through its real interface (egui_kittest: widgets found by
//! their labels, clicked, the state checked).
use eframe::egui::{self, vec2};
use et_core::ScanConfig;
use et_core::protocol::ProtocolKind;
use et_host::live::{ProtocolChoice, Source, SourceSpec};
use et_sim::touch::Touch;
use std::path::PathBuf;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

use et_host::viewer::*;

/// The viewer in a harness. A live source asks for a repaint every frame, so the harness's
/// build (which runs until no repaint is asked, at most `max_steps`) is held to a few frames:
/// each test steps the frames it needs itself (with 10 000 the build alone simulated 10 000
/// frames, most of a test's time).
fn harness(options: Options) -> Harness<'static, Viewer> {
    let viewer = Viewer::new(options).unwrap();
    Harness::builder()
        .with_size(vec2(1280.0, 800.0))
        .with_max_steps(2)
        .build_ui_state(|ui, v: &mut Viewer| v.ui(ui), viewer)
}

fn sim_options() -> Options {
    Options {
        scene: None,
        source: SourceSpec::Sim,
        model: None,
        method: et_recon::Method::default(),
        reference_frames: 20,
        realtime: false,
        screenshot: None,
        press: None,
        left_out: Vec::new(),
    }
}

/// The viewer on the simulated sheet of the scene `path`, V_0 taken from 4 frames.
fn settled_on(path: std::path::PathBuf) -> Harness<'static, Viewer> {
    let mut h = harness(Options {
        scene: Some(path),
        reference_frames: 4,
        ..sim_options()
    });
    settle(&mut h);
    h
}

/// The protocol the source scans now.
fn scanning(h: &Harness<'static, Viewer>) -> ProtocolKind {
    h.state()
        .source
        .as_ref()
        .unwrap()
        .config()
        .unwrap()
        .protocol
}

/// Steps until the reference is taken (one simulated frame per step).
fn settle(h: &mut Harness<'static, Viewer>) {
    for _ in 0..60 {
        h.step();
        if h.state()
            .last
            .as_ref()
            .is_some_and(|o| o.referencing.is_none())
        {
            return;
        }
    }
    panic!("no reference after 60 frames: {}", h.state().status);
}

#[test]
fn protocol_buttons_switch_the_scan_and_take_a_new_reference() {
    let mut h = harness(sim_options());
    settle(&mut h);
    assert_eq!(scanning(&h), ProtocolKind::Adjacent);
    for (label, kind) in [
        ("PP", ProtocolKind::PseudoPolar),
        ("PP-PP", ProtocolKind::PpPp),
        ("opposite", ProtocolKind::Opposite),
        ("AD", ProtocolKind::Adjacent),
    ] {
        h.get_by_label(label).click();
        h.step();
        h.step();
        let v = h.state();
        assert_eq!(v.protocol, ProtocolChoice::Fixed(kind));
        let last = v.last.as_ref().unwrap();
        assert_eq!(last.frame.config.protocol, kind, "{label}");
        // A new V_0 for the new protocol.
        assert!(last.referencing.is_some(), "{label}");
    }
    // A scan the source was put on behind the viewer's back (a board keeps its scan from
    // before the viewer connected) is the one shown chosen.
    let config = h.state().source.as_ref().unwrap().config().unwrap();
    (h.state_mut().source.as_mut().unwrap())
        .configure(ScanConfig {
            protocol: ProtocolKind::PpPp,
            ..config
        })
        .unwrap();
    h.step();
    h.step();
    assert_eq!(
        h.state().protocol,
        ProtocolChoice::Fixed(ProtocolKind::PpPp)
    );
    // Automatic: starts on AD.
    h.get_by_label("automatic").click();
    h.step();
    assert_eq!(h.state().protocol, ProtocolChoice::Automatic);
    assert_eq!(scanning(&h), ProtocolKind::Adjacent);
}

#[test]
fn automatic_selection_moves_to_pseudo_polar_for_a_central_press() {
    let mut h = harness(sim_options());
    h.get_by_label("automatic").click();
    // V_0 of AD, PP and PP-PP in turn, the sheet untouched; then AD.
    let mut scanned = Vec::new();
    for _ in 0..200 {
        h.step();
        if scanned.last() != Some(&scanning(&h)) {
            scanned.push(scanning(&h));
        }
        if h.state().status.contains("taken: touches show") {
            break;
        }
    }
    assert_eq!(
        scanned,
        [
            ProtocolKind::Adjacent,
            ProtocolKind::PseudoPolar,
            ProtocolKind::PpPp,
            ProtocolKind::Adjacent
        ],
        "{}",
        h.state().status
    );
    settle(&mut h);
    // A press in the middle of the sheet (docs/method.md §8: central, switch to PP).
    h.state_mut().press(vec![Touch {
        position: [0.005, 0.0],
        radius: 0.0075,
        pressure: 30e3,
        footprint: Default::default(),
    }]);
    let mut switched = false;
    for _ in 0..20 {
        h.step();
        if scanning(&h) == ProtocolKind::PseudoPolar {
            switched = true;
            break;
        }
    }
    assert!(switched, "{}", h.state().status);
    // The press held: imaged on PP where it is (against a V_0 of the untouched sheet, not
    // one taken with the press that made the switch), and the scan stays on PP.
    for _ in 0..30 {
        h.step();
    }
    let last = h.state().last.as_ref().unwrap();
    assert_eq!(last.frame.config.protocol, ProtocolKind::PseudoPolar);
    let e = last.event.clone().unwrap_or_else(|| {
        panic!(
            "the held press is not imaged on PP: referencing {:?}, status {}",
            last.referencing,
            h.state().status
        )
    });
    assert!(e.position_mm[0].hypot(e.position_mm[1]) < 15.0, "{e:?}");
}

#[test]
fn pressing_the_simulated_sheet_shows_the_touch_where_it_is() {
    let mut h = harness(sim_options());
    settle(&mut h);
    h.state_mut().press(vec![Touch {
        position: [0.03, -0.03],
        radius: 0.0075,
        pressure: 30e3,
        footprint: Default::default(),
    }]);
    h.step();
    h.step();
    let e = h
        .state()
        .last
        .as_ref()
        .unwrap()
        .event
        .clone()
        .expect("a touch");
    let off = (e.position_mm[0] - 30.0).hypot(e.position_mm[1] + 30.0);
    assert!(off < 15.0, "{e:?}");
    // The touch panel says so.
    assert!(h.query_by_label_contains("intensity z =").is_some());
    h.state_mut().press(Vec::new());
    h.step();
    h.step();
    assert!(h.state().last.as_ref().unwrap().event.is_none());
    assert!(h.query_by_label("no touch").is_some());
}

/// The GREIT button images with GREIT (alpha's slider off), and a press shows where it is.
#[test]
fn greit_images_a_press_where_it_is() {
    let mut h = harness(sim_options());
    settle(&mut h);
    h.get_by_label("GREIT").click();
    h.step();
    assert_eq!(
        h.state().processor.settings().method,
        et_recon::Method::Greit { radius: None }
    );
    h.state_mut().press(vec![Touch {
        position: [0.03, -0.03],
        radius: 0.0075,
        pressure: 30e3,
        footprint: Default::default(),
    }]);
    h.step();
    h.step();
    let e = h
        .state()
        .last
        .as_ref()
        .unwrap()
        .event
        .clone()
        .expect("a touch");
    let off = (e.position_mm[0] - 30.0).hypot(e.position_mm[1] + 30.0);
    assert!(off < 15.0, "{e:?}");
    h.get_by_label("one-step Gauss-Newton").click();
    h.step();
    assert_eq!(
        h.state().processor.settings().method,
        et_recon::Method::default()
    );
}

#[test]
fn sources_switch_between_simulator_and_recording_and_bad_paths_are_refused() {
    // A recording of the simulator to switch to.
    let dir = std::env::temp_dir().join(format!("et-viewer-src-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.jsonl");
    write_recording(&path, 30);

    let mut h = harness(sim_options());
    settle(&mut h);
    h.get_by_label("Recording").click();
    h.step();
    // No path yet: refused with a hint, the simulator keeps running.
    h.get_by_label("Open").click();
    h.step();
    assert!(h.state().status.contains("path"), "{}", h.state().status);
    assert!(matches!(h.state().source, Some(Source::Sim(_))));
    // A path that does not exist: the error names it.
    h.state_mut().source_bar.replay_path = dir.join("missing.jsonl").display().to_string();
    h.get_by_label("Open").click();
    h.step();
    assert!(
        h.state().status.contains("missing.jsonl"),
        "{}",
        h.state().status
    );
    // The recording.
    h.state_mut().source_bar.replay_path = path.display().to_string();
    h.get_by_label("Open").click();
    h.step();
    assert!(
        matches!(h.state().source, Some(Source::Replay(_))),
        "{}",
        h.state().status
    );
    assert!(h.query_all_by_label_contains("recording:").count() >= 1);
    // And back to the simulator.
    h.get_by_label("Simulated sheet").click();
    h.step();
    h.get_by_label("Open").click();
    h.step();
    assert!(matches!(h.state().source, Some(Source::Sim(_))));
    // A recording cannot change its protocol: the status says why.
    h.state_mut().source_bar.replay_path = path.display().to_string();
    h.get_by_label("Recording").click();
    h.step();
    h.get_by_label("Open").click();
    h.step();
    h.get_by_label("PP").click();
    h.step();
    assert!(
        h.state().status.contains("recorded"),
        "{}",
        h.state().status
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A model's classes are places on the sheet it was trained on: when the scene's sheet
/// changes under the viewer (its file edited, then the source opened again), the model is
/// checked against the new sheet and let go, said in the status (it was moved over without
/// the check `et stream` and the viewer's start make).
#[test]
fn a_model_of_another_sheet_is_let_go_when_the_sheet_changes() {
    use et_learn::collect;
    let dir = std::env::temp_dir().join(format!("et-viewer-sheet-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(scene("square-13cm-16.toml")).unwrap();
    let path = dir.join("sheet.toml");
    std::fs::write(&path, &text).unwrap();
    let spec = et_sim::scene::Scene::load(&path).unwrap();
    let config = collect::training_config(spec.scan_config().unwrap());
    let centres = collect::grid(&spec.sheet, 2, 2, 0.0);
    let plan = collect::Plan {
        visits: 2,
        scans: 2,
        seed: 3,
        ..collect::Plan::default()
    };
    let data = collect::collect(&spec.sheet, spec.frontend, config, &centres, &plan).unwrap();
    let trained = et_learn::Trainer {
        shrinkage: Some(0.5),
        ..et_learn::Trainer::qda()
    }
    .train(et_learn::Examples::Dataset(&data), |_| {})
    .unwrap();
    let model = dir.join("model.json");
    trained.model.save(&model).unwrap();
    let mut h = harness(Options {
        scene: Some(path.clone()),
        model: Some(model),
        ..sim_options()
    });
    h.step();
    assert!(h.state().processor.classifier.is_some());
    // The same file, opened again: the model stays.
    h.get_by_label("Simulated sheet").click();
    h.step();
    h.get_by_label("Open").click();
    h.step();
    assert!(
        h.state().processor.classifier.is_some(),
        "{}",
        h.state().status
    );
    // Its sheet made 17 cm: the model is let go, and the status says why.
    std::fs::write(
        &path,
        text.replace("width = 0.13, height = 0.13", "width = 0.17, height = 0.17"),
    )
    .unwrap();
    h.get_by_label("Open").click();
    h.step();
    let status = &h.state().status;
    assert!(
        h.state().processor.classifier.is_none()
            && status
                .contains("the model is no longer used: the model was trained on another sheet"),
        "{status}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn write_recording(path: &std::path::Path, frames: usize) {
    crate::live::write_sim_recording(path, frames);
}

#[test]
fn replay_pauses_and_seeks() {
    let dir = std::env::temp_dir().join(format!("et-viewer-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("r.jsonl");
    write_recording(&path, 40);
    let mut h = harness(Options {
        scene: None,
        source: SourceSpec::Replay(path.clone()),
        ..sim_options()
    });
    for _ in 0..5 {
        h.step();
    }
    let position = |h: &Harness<'static, Viewer>| match &h.state().source {
        Some(Source::Replay(r)) => r.position,
        _ => panic!("not a replay"),
    };
    let playing = position(&h);
    assert!(playing >= 5, "{playing}");
    h.get_by_label("Pause").click();
    h.step();
    let paused_at = position(&h);
    for _ in 0..5 {
        h.step();
    }
    assert_eq!(position(&h), paused_at, "paused, yet frames came");
    // Seek with the slider (through accesskit, as a screen reader would).
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "seek")
        .set_value_accesskit(30.0);
    h.step();
    assert_eq!(position(&h), 30);
    // The frame counter says where the replay is, out of how many.
    h.step();
    assert!(h.query_by_label("frame 30 of 40").is_some());
    h.get_by_label("Play").click();
    h.step();
    h.step();
    assert!(position(&h) > 30);
    // A seek forward is no frame lost (link health said "lost (gaps)" 25), and one back keeps
    // the BVC plot's time running to now (it plotted each frame at its time in the file).
    assert_eq!(h.state().monitor.gaps, 0);
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "seek")
        .set_value_accesskit(22.0);
    for _ in 0..12 {
        h.step();
    }
    let state = h.state();
    assert_eq!(state.monitor.gaps, 0);
    let times: Vec<f64> = state.monitor.bvc.iter().map(|p| p.0).collect();
    assert!(
        times.len() > 3 && times.windows(2).all(|w| w[0] <= w[1]),
        "{times:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Automatic selection (and the wizard) cannot switch a recording's scan: refused, its V_0
/// kept and the recorded protocol still chosen (the V_0 was taken again from the frames playing, a press
/// among them, and "automatic" stayed lit over an image of noise).
#[test]
fn automatic_selection_and_the_wizard_are_refused_on_a_recording() {
    let dir = std::env::temp_dir().join(format!("et-viewer-auto-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("r.jsonl");
    write_recording(&path, 40);
    let mut h = harness(Options {
        source: SourceSpec::Replay(path.clone()),
        reference_frames: 2,
        ..sim_options()
    });
    settle(&mut h);
    let v0 = h.state().processor.v0();
    assert!(v0.is_some());
    h.get_by_label("automatic").click();
    for _ in 0..25 {
        h.step();
    }
    let state = h.state();
    assert!(
        state.processor.v0() == v0,
        "V_0 taken again: {}",
        state.status
    );
    assert_eq!(
        state.protocol,
        ProtocolChoice::Fixed(ProtocolKind::Adjacent)
    );
    assert!(
        state.status.contains("which a recording cannot"),
        "{}",
        state.status
    );
    // The wizard likewise: it waited without end for frames of its scan (opposite), which a
    // recording of adjacent never sends.
    // Clicked as a user clicks, while the recording's touches come and go above the button
    // (they moved it, and the click missed).
    h.get_by_label("Open the training wizard").click();
    h.step();
    h.step();
    assert!(h.state().wizard.open);
    h.get_by_label("Start").click();
    for _ in 0..5 {
        h.step();
    }
    let wizard = &h.state().wizard;
    assert!(
        matches!(wizard.step, wizard::Step::Setup),
        "{:?}",
        wizard.step
    );
    assert!(
        wizard
            .message
            .contains("open the simulated sheet or a board"),
        "{}",
        wizard.message
    );
    assert!(h.state().processor.v0() == v0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_wizard_collects_trains_and_the_model_classifies() {
    let mut h = harness(sim_options());
    settle(&mut h);
    h.get_by_label("Open the training wizard").click();
    h.step();
    {
        let w = &mut h.state_mut().wizard;
        w.rows = 2;
        w.cols = 2;
        w.visits = 2;
        w.frames_per_press = 8;
    }
    h.step();
    h.get_by_label("Start").click();
    // Press every cell of every visit with the simulator's help.
    let mut presses = 0;
    for _ in 0..400 {
        h.step();
        if h.state().wizard.step == wizard::Step::Ready {
            break;
        }
        if let Some(b) = h.query_by_label("Press for me (simulated)") {
            b.click();
            presses += 1;
            // The click lands on the next step; the step after shows the new state.
            h.step();
        }
    }
    assert_eq!(
        h.state().wizard.step,
        wizard::Step::Ready,
        "{}",
        h.state().wizard.message
    );
    assert_eq!(presses, 8, "2 x 2 cells, 2 visits");
    assert_eq!(h.state().wizard.observations(), 4 * 2 * 8);
    h.get_by_label("Train").click();
    h.step();
    h.step();
    let w = &h.state().wizard;
    assert_eq!(w.step, wizard::Step::Trained, "{}", w.message);
    let acc = w.trained.as_ref().unwrap().cv.accuracy();
    assert!(acc > 0.9, "cross-validated accuracy {acc}");
    assert!(
        h.query_all_by_label_contains("cross-validated accuracy")
            .count()
            >= 1
    );
    // Saving over an existing file asks first (a second Save replaces it), whole files only.
    let dir = std::env::temp_dir().join(format!("et-wizard-save-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.json");
    std::fs::write(&path, "an older model").unwrap();
    h.state_mut().wizard.save_path = path.display().to_string();
    h.get_by_label("Save").click();
    h.step();
    assert!(h.state().wizard.message.contains("Save again to replace"));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "an older model");
    h.get_by_label("Save").click();
    h.step();
    assert!(
        h.state().wizard.message.starts_with("saved"),
        "{}",
        h.state().wizard.message
    );
    et_learn::model_file::ModelFile::load(&path).unwrap();
    let blob = std::fs::read(dir.join("model.etm")).unwrap();
    // A model named .etm was written there, then replaced by its own blob.
    h.state_mut().wizard.save_path = dir.join("model.etm").display().to_string();
    for _ in 0..2 {
        h.get_by_label("Save").click();
        h.step();
        let message = &h.state().wizard.message;
        assert!(message.contains("written as .json"), "{message}");
    }
    assert_eq!(std::fs::read(dir.join("model.etm")).unwrap(), blob);
    // The viewer's inputs (here the model it was given) are never replaced, even on a
    // second Save, as et's commands refuse theirs.
    let given = dir.join("given.json");
    std::fs::write(&given, "the model given").unwrap();
    h.state_mut().wizard.save_path = given.display().to_string();
    for _ in 0..2 {
        let message = h.state_mut().wizard.save(std::slice::from_ref(&given));
        assert!(message.contains("this is the input"), "{message}");
    }
    assert_eq!(std::fs::read_to_string(&given).unwrap(), "the model given");
    assert!(!dir.join("given.etm").exists());
    std::fs::remove_dir_all(&dir).unwrap();
    // Without a board, export is disabled; the model can be used here.
    h.get_by_label("Use this model").click();
    h.step();
    assert!(h.state().processor.classifier.is_some());
    // The wizard scans the opposite protocol, as the model expects: press each cell and
    // the class grid lights that cell.
    let sheet = et_host::live::default_scene().unwrap().sheet;
    let centres = et_learn::collect::grid(&sheet, 2, 2, 0.0);
    for (c, centre) in centres.iter().enumerate() {
        h.state_mut().press(vec![Touch {
            position: *centre,
            radius: 0.0075,
            pressure: 30e3,
            footprint: Default::default(),
        }]);
        h.step();
        h.step();
        let last = h.state().last.as_ref().unwrap();
        let e = last.event.clone().unwrap_or_else(|| {
            panic!(
                "no touch: referencing {:?}, frame {:?} {:?}, status {}",
                last.referencing,
                last.frame.config.protocol,
                last.frame.truth,
                h.state().status
            )
        });
        assert_eq!(e.class, Some(c as u16), "{e:?}");
        assert!(h.query_by_label(&format!("class {c}")).is_some());
    }
}

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../sim/scenes")
        .join(name)
}

/// Steps until the scene's touches are on the sheet (the simulated source holds them back for
/// its first [`et_host::live::SimSource::LEAD_FRAMES`] frames).
fn until_pressed(h: &mut Harness<'static, Viewer>) {
    for _ in 0..2 * et_host::live::SimSource::LEAD_FRAMES {
        h.step();
        let truth = h.state().last.as_ref().and_then(|o| o.frame.truth.as_ref());
        if truth.is_some_and(|t| !t.is_empty()) {
            return;
        }
    }
    panic!("the scene's touches never came: {}", h.state().status);
}

/// Steps until the frame is a touch (at most `n` frames).
fn until_touched(h: &mut Harness<'static, Viewer>, n: usize) -> et_host::live::TouchEvent {
    for _ in 0..n {
        h.step();
        if let Some(e) = h.state().last.as_ref().and_then(|o| o.event.clone()) {
            // One more frame so that the view draws what this one found.
            h.step();
            return e;
        }
    }
    panic!("no touch after {n} frames: {}", h.state().status);
}

#[test]
fn the_sheet_is_drawn_in_mm_with_numbered_electrodes_a_labelled_colour_bar_and_plot_axes() {
    let mut h = harness(sim_options());
    settle(&mut h);
    h.step();
    let v = h.state();
    let d = &v.sheet_view.drawn;
    // The axes: round mm on both, zero among them (the sheet is centred on the origin), and
    // every tick inside the image's extent.
    let b = v.sheet.physical.shape.bounds();
    for (ticks, (lo, hi)) in [(&d.ticks_mm.0, (b[0], b[2])), (&d.ticks_mm.1, (b[1], b[3]))] {
        assert!(ticks.len() >= 3, "{ticks:?}");
        assert!(ticks.contains(&"0".to_string()), "{ticks:?}");
        for t in ticks {
            let mm: f64 = t.parse().unwrap();
            assert_eq!(mm.fract(), 0.0, "{t}");
            assert!(
                mm >= lo * 1e3 - 5.0 && mm <= hi * 1e3 + 5.0,
                "{t} outside {lo}..{hi} m"
            );
        }
    }
    // Every electrode, numbered from 0 as `et protocol` counts, on the outline.
    let count = usize::from(v.sheet.physical.electrodes.count);
    assert_eq!(d.electrodes.len(), count);
    for (k, (e, at)) in d.electrodes.iter().enumerate() {
        assert_eq!(*e, k);
        let off = v
            .sheet
            .physical
            .shape
            .distance_to_outline([at[0] * 1e-3, at[1] * 1e-3]);
        assert!(off < 1e-6, "electrode {e} {off} m off the outline");
    }
    // The colour bar: captioned, ticks symmetric about a zero in the middle.
    assert_eq!(d.colour_bar.0, "Δσ/σ0");
    let ticks = &d.colour_bar.1;
    assert!(
        ticks.contains(&"0".to_string()) || ticks.contains(&"0.0".to_string()),
        "{ticks:?}"
    );
    let values: Vec<f64> = ticks.iter().map(|t| t.parse().unwrap()).collect();
    let mut mirrored: Vec<f64> = values.iter().map(|v| -v).collect();
    mirrored.reverse();
    assert_eq!(values, mirrored, "{ticks:?}");
    // The small plots' axes: time to now, channels 1..K.
    let axes = &v.plots.axes;
    for label in ["time", "now", "channel k", "1"] {
        assert!(axes.iter().any(|a| a == label), "{label} not in {axes:?}");
    }
    let k = v.last.as_ref().unwrap().frame.voltages.len();
    assert!(axes.contains(&k.to_string()), "{k} not in {axes:?}");
}

#[test]
fn two_touches_get_two_numbered_markers_and_outlines_and_specks_only_on_request() {
    let mut h = harness(Options {
        scene: Some(scene("disc-ref-two.toml")),
        ..sim_options()
    });
    settle(&mut h);
    until_pressed(&mut h);
    until_touched(&mut h, 30);
    let d = h.state().sheet_view.drawn.clone();
    assert_eq!(d.truth, 2, "{d:?}");
    assert_eq!(d.touches.len(), 2, "{d:?}");
    assert_eq!(d.outlines, 2, "one outline per found touch: {d:?}");
    assert!(!d.specks);
    assert_eq!(
        d.touches.iter().map(|t| t.0).collect::<Vec<_>>(),
        [1, 2],
        "numbered from the strongest"
    );
    // Each marker sits on a true touch (the scene's are 110 mm apart).
    let truth = h
        .state()
        .last
        .as_ref()
        .unwrap()
        .frame
        .truth
        .clone()
        .unwrap();
    for (n, at) in &d.touches {
        let off = truth
            .iter()
            .map(|t| (t.position[0] * 1e3 - at[0]).hypot(t.position[1] * 1e3 - at[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(
            off < 15.0,
            "touch {n} at {at:?} is {off:.1} mm from the truth"
        );
    }
    // The panel agrees with the picture.
    assert!(h.query_by_label("2 region(s)").is_some());
    // The specks' outline on request.
    h.get_by_label("outline every pixel >= f max").click();
    h.step();
    h.step();
    assert!(h.state().sheet_view.show_specks);
    assert!(h.state().sheet_view.drawn.specks);
}

#[test]
fn a_screenshot_presses_only_where_asked() {
    let shot = Some(std::env::temp_dir().join("et-never-written.png"));
    // Asked: a press at (30, 25) mm shows there, with one outline and one marker.
    let mut h = harness(Options {
        screenshot: shot.clone(),
        press: Some([30.0, 25.0]),
        ..sim_options()
    });
    settle(&mut h);
    until_touched(&mut h, 20);
    let d = h.state().sheet_view.drawn.clone();
    assert_eq!((d.touches.len(), d.outlines, d.truth), (1, 1, 1), "{d:?}");
    let at = d.touches[0].1;
    assert!((at[0] - 30.0).hypot(at[1] - 25.0) < 10.0, "{at:?}");
    // Not asked: the untouched default sheet stays untouched.
    let mut h = harness(Options {
        screenshot: shot,
        press: None,
        ..sim_options()
    });
    settle(&mut h);
    for _ in 0..20 {
        h.step();
    }
    let d = &h.state().sheet_view.drawn;
    assert!(h.state().last.as_ref().unwrap().event.is_none());
    assert_eq!((d.touches.len(), d.outlines, d.truth), (0, 0, 0), "{d:?}");
}

/// The simulated sheet with electrode 3 disconnected (the simulator's fault: its input floats
/// to a rail, its injections drive nothing): once V_0 is taken the status line names
/// electrode 3 and the side panel offers to leave it out, which leaves its 52 values out of
/// the images; put back, it is offered again. The sound sheet's names none and offers none.
#[test]
fn a_disconnected_electrode_is_named_in_the_status_and_left_out() {
    let dir = std::env::temp_dir().join(format!("et-viewer-fault-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let sound = std::fs::read_to_string(scene("square-13cm-16.toml")).unwrap();
    for faulty in [false, true] {
        let path = dir.join(format!("fault-{faulty}.toml"));
        let fault = "\n[[fault]]\nelectrode = 3\nkind = \"disconnected\"\n";
        std::fs::write(&path, sound.clone() + if faulty { fault } else { "" }).unwrap();
        let mut h = settled_on(path);
        let status = &h.state().status;
        assert_eq!(
            status.contains("warning: electrode 3's 52 values"),
            faulty,
            "{status}"
        );
        h.step();
        let offered = h.query_by_label("Leave out electrode 3").is_some();
        assert_eq!(offered, faulty);
        if !faulty {
            continue;
        }
        h.get_by_label("Leave out electrode 3").click();
        h.step();
        h.step();
        let v = h.state();
        assert_eq!(v.processor.left_out(), [3]);
        assert!(
            v.status
                == "electrode 3 left out of the images: 52 of the frame's 208 values \
                         (every value they drive or measure)",
            "{}",
            v.status
        );
        assert!(h.query_by_label("Leave out electrode 3").is_none());
        // The wizard started now would train on its values: said.
        h.get_by_label("Open the training wizard").click();
        h.step();
        h.step();
        h.get_by_label("Start").click();
        h.step();
        h.step();
        let status = &h.state().status;
        assert!(
            status
                .starts_with("warning: the wizard's model trains on whole frames, and electrode 3"),
            "{status}"
        );
        h.state_mut().wizard.open = false;
        h.step();
        h.get_by_label("Put back").click();
        h.step();
        h.step();
        assert!(h.state().processor.left_out().is_empty());
        assert!(h.query_by_label("Leave out electrode 3").is_some());
        // What the status said of V_0, replaced since, stays to read.
        assert!(
            h.query_by_label_contains("warning: electrode 3's 52 values")
                .is_none()
        );
        h.get_by_label_contains("Earlier messages").click();
        h.step();
        h.step();
        assert!(
            h.query_by_label_contains("warning: electrode 3's 52 values")
                .is_some()
        );
    }
    // A gain four times the sheet's: its largest readings clip, which the board flags, and
    // V_0 says so (before the poor fit the clipped values also leave).
    let path = dir.join("gain.toml");
    assert!(sound.contains("\ngain = 8 "));
    std::fs::write(&path, sound.replace("\ngain = 8 ", "\ngain = 32 ")).unwrap();
    let h = settled_on(path);
    let status = &h.state().status;
    assert!(
        status.starts_with(
            "V_0 taken; warning: the board flagged readings with samples on an ADC rail"
        ) && status.contains("in frames of V_0"),
        "{status}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A replay of the simulated sheet whose electrode 3 comes off at frame 10 and is put back at
/// frame 30 (frames of the sound and the disconnected sheet, one seed): the status names it
/// off, the side panel offers to leave it out; once it fits the model 10 frames in a row the
/// status says it back and the offer goes.
#[test]
fn an_electrode_put_back_is_said_back_and_no_longer_offered_to_leave_out() {
    let dir = std::env::temp_dir().join(format!("et-viewer-back-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let sound = std::fs::read_to_string(scene("square-13cm-16.toml")).unwrap();
    let (sound_path, off_path) = (dir.join("sound.toml"), dir.join("off.toml"));
    std::fs::write(&sound_path, &sound).unwrap();
    let fault = "\n[[fault]]\nelectrode = 3\nkind = \"disconnected\"\n";
    std::fs::write(&off_path, sound + fault).unwrap();
    let frames = |path: &std::path::Path| {
        let (mut source, _) = et_host::live::open_source(&SourceSpec::Sim, Some(path)).unwrap();
        let frames: Vec<_> = (0..60)
            .flat_map(|_| source.poll(1, false).unwrap())
            .collect();
        frames
    };
    let (sound, off) = (frames(&sound_path), frames(&off_path));
    let spliced: Vec<_> = (0..60)
        .map(|i| {
            if (10..30).contains(&i) {
                &off[i]
            } else {
                &sound[i]
            }
        })
        .collect();
    let path = dir.join("back.jsonl");
    crate::live::write_recording(&path, &spliced);
    let mut h = harness(Options {
        scene: Some(sound_path),
        source: SourceSpec::Replay(path),
        reference_frames: 4,
        ..sim_options()
    });
    let mut offered = false;
    for _ in 0..40 {
        h.step();
        offered |= h.query_by_label("Leave out electrode 3").is_some();
    }
    let state = h.state();
    let said: Vec<&str> = std::iter::once(state.status.as_str())
        .chain(state.said.earlier().map(|(said, _)| said))
        .collect();
    assert!(
        said.iter()
            .any(|s| s.starts_with("frame 10: electrode 3's 52 values")),
        "{said:?}"
    );
    assert!(offered);
    assert!(
        said.iter().any(|s| s.starts_with(
            "frame 39: electrode 3's values fit the model again from frame 30 (off since \
             frame 10): it is back"
        )),
        "{said:?}"
    );
    assert!(h.query_by_label("Leave out electrode 3").is_none());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The window's error is said without winit's type and the place in its source (a path
/// under ~/.cargo and a line number were said to the user); another error as it is.
#[test]
fn the_window_s_error_is_said_without_winit_s_source_place() {
    let e = "winit EventLoopError: os error at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set.";
    assert_eq!(
        window_said(e),
        "neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set"
    );
    assert_eq!(window_said("no GPU adapter found"), "no GPU adapter found");
}

/// The status log keeps each message once, the most recent last, counts one said again, and
/// keeps at most `StatusLog::KEPT`, the oldest going first.
#[test]
fn the_status_line_s_earlier_messages_stay_to_read() {
    use et_host::viewer::StatusLog;
    let mut log = StatusLog::default();
    for now in ["a", "a", "", "b", "a", "c"] {
        log.note(now);
    }
    let earlier: Vec<(&str, u32)> = log.earlier().collect();
    assert_eq!(earlier, [("a", 2), ("b", 1)]);
    for i in 0..2 * StatusLog::KEPT {
        log.note(&i.to_string());
    }
    let earlier: Vec<(&str, u32)> = log.earlier().collect();
    assert_eq!(earlier.len(), StatusLog::KEPT - 1);
    let newest = (2 * StatusLog::KEPT - 2).to_string();
    assert_eq!(earlier.first(), Some(&(newest.as_str(), 1)));
}
