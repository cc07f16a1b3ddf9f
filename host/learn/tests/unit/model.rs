//! The one model type: either kind loaded from its file, predicting as the kind's own code
//! does, classifying frames as the live pipeline does, and refusing the other kind's calls.

use et_core::ScanConfig;
use et_core::model::Precision;
use et_core::protocol::{Halving, Protocol, ProtocolKind};
use et_core::rng::Rng;
use et_learn::Trainer;
use et_learn::dataset::Dataset;
use et_learn::dataset::Unit;
use et_learn::model::*;
use et_learn::tabular::{Choice, Kind, Table};
use nalgebra::DMatrix;
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("et-model-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Three classes of frames (opposite drive, L = 8: K = 32, the 16 reciprocity-halved values
/// as features), each class shifting the frame its own way, in two visits with their own
/// untouched frames: the referenced features V_m - V_0 separate the classes.
fn dataset() -> Dataset {
    let protocol = Protocol::new(ProtocolKind::Opposite, 8).unwrap();
    let feature_index: Vec<u16> = protocol
        .features(Halving::Reciprocity)
        .map(|k| k as u16)
        .collect();
    let p = feature_index.len();
    let mut rng = Rng::new(5);
    let baselines = DMatrix::from_fn(2, p, |v, j| 0.05 + 0.01 * v as f64 + 1e-3 * j as f64);
    let shift = |c: usize, j: usize| 2e-3 * ((c * 7 + j * 3) % 5) as f64;
    let (classes, per_class) = (3, 60);
    let n = classes * per_class;
    let (y, visit): (Vec<u16>, Vec<u16>) = (0..n).map(|r| ((r % 3) as u16, (r % 2) as u16)).unzip();
    let x = DMatrix::from_fn(n, p, |r, j| {
        baselines[(usize::from(visit[r]), j)]
            + shift(usize::from(y[r]), j)
            + 3e-4 * (1.0 + f64::from(y[r])) * rng.normal()
    });
    Dataset {
        x,
        positions: (0..n).map(|r| [0.02 * f64::from(y[r]), 0.01]).collect(),
        pressure: vec![2e4; n],
        // Eight on a circle of 50 mm radius, from angle 0.
        electrodes: (0..8)
            .map(|e| {
                let a = std::f64::consts::FRAC_PI_4 * f64::from(e);
                [0.05 * a.cos(), 0.05 * a.sin()]
            })
            .collect(),
        centres: vec![[0.0, 0.01], [0.02, 0.01], [0.04, 0.01]],
        y,
        visit,
        feature_index,
        baselines,
        config: ScanConfig {
            protocol: ProtocolKind::Opposite,
            electrodes: 8,
            ..ScanConfig::REFERENCE
        },
    }
}

/// Training on an et dataset says its estimated time before its work and is held to the
/// budget as a table's training is (a 100 x 100 grid, 10 000 classes, trained for minutes
/// and held 11 GB without a word); the memory it holds grows with the classes, each fold's
/// statistics a p x p table per class.
#[test]
fn a_datasets_training_says_its_time_first_and_keeps_to_the_budget() {
    use et_learn::pipeline::cost::Shape;
    use et_learn::trainer::{Progress, TrainError};
    let data = dataset();
    let mut said = Vec::new();
    let trained = Trainer::qda()
        .train(Examples::Dataset(&data), |p| said.push(p.said(10).0))
        .unwrap();
    // Frames that tell the classes apart are better than guessing; the same frames dealt to
    // other rows (labels that do not belong to them) are not, and are said so.
    let cv = |t: et_learn::trainer::Trained| t.board.unwrap().training.cv;
    assert_eq!(cv(trained).no_better_than_guessing(), None);
    let mut dealt = data.clone();
    let mut rng = Rng::new(8);
    let mut order: Vec<usize> = (0..data.x.nrows()).collect();
    for r in (1..order.len()).rev() {
        order.swap(r, rng.next_u32() as usize % (r + 1));
    }
    dealt.x = data.x.select_rows(&order);
    let guessed = cv(Trainer::qda()
        .train(Examples::Dataset(&dealt), |_| {})
        .unwrap());
    let note = guessed.no_better_than_guessing().map(|g| g.to_string());
    assert!(
        note.as_deref()
            .is_some_and(|n| n.contains("commonest class")),
        "{note:?} at {} %",
        100.0 * guessed.accuracy()
    );
    let estimate = said.iter().position(|s| s.starts_with("training: "));
    let statistics = said.iter().position(|s| s == "each fold's statistics");
    assert!(
        estimate.is_some() && estimate < statistics,
        "the estimate before the work: {said:?}"
    );
    let tight = Trainer {
        budget_s: 1e-9,
        ..Trainer::qda()
    };
    let e = tight
        .train(Examples::Dataset(&data), |_: Progress<'_>| {})
        .unwrap_err();
    assert!(matches!(e, TrainError::OverBudget { .. }), "{e}");
    assert!(
        e.to_string().contains("fewer classes (et collect --grid)"),
        "{e}"
    );
    // One observation of a class leaves it nothing to fit on in the fold holding it out
    // (said as "at least 2 folds (1 given)", none given): said as what it is.
    let mut one_each = data.clone();
    let first: Vec<usize> = (0..3)
        .map(|c| data.y.iter().position(|&y| y == c).unwrap())
        .collect();
    one_each.x = data.x.select_rows(&first);
    one_each.y = first.iter().map(|&r| data.y[r]).collect();
    one_each.visit = first.iter().map(|&r| data.visit[r]).collect();
    one_each.positions = first.iter().map(|&r| data.positions[r]).collect();
    one_each.pressure = first.iter().map(|&r| data.pressure[r]).collect();
    let e = (Trainer::qda().train(Examples::Dataset(&one_each), |_| {})).unwrap_err();
    assert!(
        matches!(e, TrainError::FewPerClass { class: 0, count: 1 }),
        "{e}"
    );
    // A budget of NaN passed every estimate: refused where the trainer takes it.
    let none = Trainer {
        budget_s: f64::NAN,
        ..Trainer::qda()
    };
    let e = none
        .train(Examples::Dataset(&data), |_: Progress<'_>| {})
        .unwrap_err();
    assert!(matches!(e, TrainError::Budget(_)), "{e}");
    // The statistics of 10 000 classes of 96 features in 10 folds alone are 7.4 GB; a tenth
    // of the classes holds under a tenth of it.
    let shape = |classes: usize| Shape {
        n: 20 * classes,
        p: 96,
        classes,
        folds: 10,
        visits: 1,
        choose: true,
    };
    assert!(shape(10_000).bytes() > 7_400_000_000);
    assert!(shape(1_000).bytes() < shape(10_000).bytes() / 10);
}

/// Row `r` of `data` as the whole frame the board sends (K values, its features in place),
/// and its visit's untouched frame.
fn frames_of(data: &Dataset, r: usize) -> (Vec<f64>, Vec<f64>) {
    let k = Protocol::new(data.config.protocol, data.config.electrodes)
        .unwrap()
        .frame_len();
    let (mut v, mut v0) = (vec![0.0; k], vec![0.0; k]);
    for (j, &i) in data.feature_index.iter().enumerate() {
        v[usize::from(i)] = data.x[(r, j)];
        v0[usize::from(i)] = data.baselines[(usize::from(data.visit[r]), j)];
    }
    (v, v0)
}

#[test]
fn a_board_model_loads_predicts_and_classifies_frames_one_way() {
    let data = dataset();
    let trained = Trainer::qda()
        .train(Examples::Dataset(&data), |_| {})
        .unwrap();
    assert!(
        trained.board.is_some(),
        "a board model's training comes with it"
    );
    let dir = tmp("board");
    let path = dir.join("model.json");
    trained.model.save(&path).unwrap();
    let model = Model::load(&path).unwrap();
    assert_eq!(model.method(), "qda");
    let board = model.as_board().expect("a board model");
    assert_eq!(board.file(), trained.model.as_board().unwrap().file());

    // The dataset's predictions, the frames' predictions and the live classification agree.
    let by_dataset = model.predict_dataset(&data).unwrap();
    let test = board.test(&data).unwrap();
    assert!(
        test.confusion.accuracy() > 0.9,
        "{}",
        test.confusion.accuracy()
    );
    assert_eq!(test.scale_note, None);
    // The dataset in mV (its frames and untouched frames): classified without an error, and
    // wrongly, so said as the table models say it.
    let mut in_mv = data.clone();
    in_mv.x *= 1e3;
    in_mv.baselines *= 1e3;
    let said = board.test(&in_mv).unwrap().scale_note.unwrap_or_default();
    assert!(
        said.contains("1000 times those the model was trained on"),
        "{said}"
    );
    // Data of another grid or sheet label other places with the same numbers: refused (a
    // 2 x 2 grid scored 25 % on a 3 x 3 model without a word), the same grid to rounding taken.
    let mut elsewhere = data.clone();
    elsewhere.centres[2] = [0.045, 0.01];
    let e = board.test(&elsewhere).unwrap_err().to_string();
    assert!(
        e.contains("the data's class 2 is at (45.0, 10.0) mm, the model's at (40.0, 10.0) mm"),
        "{e}"
    );
    elsewhere.centres.pop();
    let e = board.test(&elsewhere).unwrap_err().to_string();
    assert!(e.contains("the data have 2 classes, the model 3"), "{e}");
    let mut rounded = data.clone();
    rounded.centres[2][0] += 1e-9;
    board.test(&rounded).unwrap();
    // Its classes are places on the sheet it was trained on: another sheet's electrodes (one
    // 5 mm out, past a twentieth of their 38 mm spacing) refused, beside a dataset or the live
    // pipeline's sheet; a sheet or data that do not say pass.
    assert_eq!(board.file().electrodes, data.electrodes);
    board.same_sheet(&data.electrodes).unwrap();
    board.same_sheet(&[]).unwrap();
    let mut wider = data.clone();
    wider.electrodes[3][0] += 0.005;
    let e = board.test(&wider).unwrap_err().to_string();
    assert!(
        e.contains("its electrode 4 was at (-35.4, 35.4) mm, this sheet's is at (-30.4, 35.4) mm"),
        "{e}"
    );
    let e = (board.same_sheet(&data.electrodes[1..]).unwrap_err()).to_string();
    assert!(e.contains("a sheet of 8 electrodes, this one has 7"), "{e}");
    wider.electrodes.clear();
    board.test(&wider).unwrap();
    // A file whose electrodes are not one per electrode of its scan is refused where read.
    let text = std::fs::read_to_string(&path).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value["electrodes_m"].as_array_mut().unwrap().pop();
    let short = dir.join("short.json");
    std::fs::write(&short, value.to_string()).unwrap();
    let e = Model::load(&short).unwrap_err().to_string();
    assert!(
        e.contains("electrodes_m") && e.contains("7 centres for a scan of 8 electrodes"),
        "{e}"
    );
    for r in (0..data.x.nrows()).step_by(7) {
        let (v, v0) = frames_of(&data, r);
        let frame = DMatrix::from_row_slice(1, v.len(), &v);
        let by_frame = model.predict(&frame, Some(&v0)).unwrap();
        assert_eq!(by_frame, by_dataset[r..=r], "row {r}");
        let live = board.classify(&data.config, &v, &v0).unwrap();
        assert_eq!(Some(live.class), by_dataset[r].class, "row {r}");
        // The softmax's largest posterior is at least 1/C.
        assert!((1.0 / 3.0..=1.0).contains(&live.posterior), "{live:?}");
        // The class's centre (m) is its prediction's position.
        let c = data.centres[usize::from(live.class)];
        let target = by_dataset[r].target.unwrap();
        assert_eq!([target[0], target[1]], c);
    }
    // Another scan's frames are not classified; a referenced model needs V_0.
    let other = ScanConfig {
        protocol: ProtocolKind::Adjacent,
        ..data.config
    };
    let (v, v0) = frames_of(&data, 0);
    assert!(board.classify(&other, &v, &v0).is_none());
    let frame = DMatrix::from_row_slice(1, v.len(), &v);
    assert!(matches!(
        model.predict(&frame, None),
        Err(ModelError::Mismatch(Mismatch::NoUntouchedFrame))
    ));
    // A frame too short for the features is refused, not read past its end.
    let short = DMatrix::from_row_slice(1, 3, &v[..3]);
    assert!(matches!(
        model.predict(&short, Some(&v0)),
        Err(ModelError::Use(UseError::FrameLength { .. }))
    ));
    // Without V_0 too: the frames are another scan's, whatever V_0 (a table's rows were asked
    // for their untouched frame).
    assert!(matches!(
        model.predict(&short, None),
        Err(ModelError::Use(UseError::FrameLength { v0: 0, .. }))
    ));

    // A value it reads that is NaN, or so large its discriminants overflow, names no class
    // (NaN frames were the last class): refused by its place; values it does not read, and
    // frames within reach, are classified as before.
    let read = usize::from(data.feature_index[2]);
    let unread = (0..v.len())
        .find(|i| !data.feature_index.contains(&(*i as u16)))
        .unwrap();
    let mut nan = v.clone();
    nan[unread] = f64::NAN;
    let by_frame =
        |v: &[f64], v0: &[f64]| board.predict_frames(&DMatrix::from_row_slice(1, v.len(), v), v0);
    assert_eq!(by_frame(&nan, &v0).unwrap(), by_frame(&v, &v0).unwrap());
    nan[read] = f64::NAN;
    let e = by_frame(&nan, &v0).unwrap_err().to_string();
    assert_eq!(
        e,
        format!("frame 0, value {read}: NaN, where a finite number belongs")
    );
    let mut v0_inf = v0.clone();
    v0_inf[read] = f64::INFINITY;
    let e = by_frame(&v, &v0_inf).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("the untouched frame, value {read}: inf")),
        "{e}"
    );
    let huge: Vec<f64> = v.iter().map(|x| x * 1e300).collect();
    let e = by_frame(&huge, &v0).unwrap_err().to_string();
    assert!(
        e.contains("observation 0: its discriminants are not finite"),
        "{e}"
    );

    // Evaluation is the test; the blob is the file's; a table is refused.
    let Evaluation::Board(evaluated) = model.evaluate(Examples::Dataset(&data)).unwrap() else {
        panic!("a board model's evaluation");
    };
    assert_eq!(evaluated.confusion, test.confusion);
    assert_eq!(
        model.export_blob(Precision::F16).unwrap(),
        board.file().blob(Precision::F16).unwrap()
    );
    assert!(board.slot_blob().unwrap().len() <= et_core::board::MODEL_SLOT_BYTES);
    let table = table();
    assert!(matches!(
        model.evaluate(Examples::Table(&table)),
        Err(ModelError::Mismatch(Mismatch::BoardOnTable))
    ));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two features, three labelled classes.
fn table() -> Table {
    let mut rng = Rng::new(9);
    let n = 90;
    let x = DMatrix::from_fn(n, 2, |r, j| {
        (r % 3) as f64 * (1.0 + j as f64) + 0.1 * rng.normal()
    });
    Table {
        feature_names: vec!["a".into(), "b".into()],
        x,
        labels: Some((0..n).map(|r| ["x", "y", "z"][r % 3].into()).collect()),
        positions: None,
        third: None,
        description: String::new(),
        first_row: 0,
        unit: Unit::Mm,
        groups: None,
    }
}

#[test]
fn a_tables_model_loads_predicts_and_refuses_the_boards_calls() {
    let table = table();
    let trainer = Trainer {
        method: Choice::One(Kind::Lda),
        folds: Some(3),
        ..Trainer::default()
    };
    let trained = trainer.train(Examples::Table(&table), |_| {}).unwrap();
    assert!(trained.board.is_none());
    let dir = tmp("table");
    let path = dir.join("model.json");
    trained.model.save(&path).unwrap();
    let model = Model::load(&path).unwrap();
    assert_eq!(model.method(), "lda");
    assert!(model.as_board().is_none());
    let before = trained.model.predict(&table.x, None).unwrap();
    assert_eq!(model.predict(&table.x, None).unwrap(), before);
    assert!(matches!(
        model.evaluate(Examples::Table(&table)).unwrap(),
        Evaluation::Table(e) if e.accuracy.unwrap() > 0.9
    ));
    for refused in [
        model.export_blob(Precision::F32).map(|_| ()),
        model.evaluate(Examples::Dataset(&dataset())).map(|_| ()),
        model.predict_dataset(&dataset()).map(|_| ()),
        model.clone().into_board().map(|_| ()),
    ] {
        assert!(
            matches!(refused, Err(ModelError::Mismatch(_))),
            "{refused:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_of_neither_kind_is_refused_naming_it() {
    let dir = tmp("neither");
    for (name, text) in [
        (
            "other.json",
            r#"{"format": "something-else", "version": 1}"#,
        ),
        ("none.json", r#"[1, 2, 3]"#),
        ("broken.json", r#"{"format": "et-model""#),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let e = Model::load(&path).unwrap_err();
        assert!(e.to_string().contains(name), "{e}");
    }
    // What each damaged file is said to be: cut short, of a later version, or a format
    // edited to the other kind's (it was read as that kind and said a field's type).
    for (text, said) in [
        (r#"{"format": "et-model""#, "the file ends inside its JSON"),
        (
            r#"{"format": "et-table-model", "version": 99, "tables": 1}"#,
            r#"version 1 or 2 ("format": "et-table-model", "version": 99"#,
        ),
        (
            r#"{"format": "et-model", "version": 3}"#,
            r#""format": "et-model", "version": 3; a later version is a newer et's"#,
        ),
        (
            r#"{"format": "xyz", "version": 2}"#,
            r#"a table's model: "format": "xyz", "version": 2)"#,
        ),
        (
            r#"{"format": "et-model", "version": 2, "feature_names": [], "tables": {}}"#,
            r#"its "format" says "et-model" (a board model), but its fields (feature_names, tables) are those of a table's model, whose format is "et-table-model""#,
        ),
        (
            r#"{"format": "et-table-model", "version": 2, "config": {}, "feature_index": []}"#,
            r#"are those of a board model, whose format is "et-model""#,
        ),
    ] {
        let path = dir.join("damaged.json");
        std::fs::write(&path, text).unwrap();
        let e = Model::load(&path).unwrap_err().to_string();
        assert!(e.contains(said), "{text}: {e}");
    }
    // A file that is not JSON at all (frames, a table or a scene given as the model): said as
    // not a model file, with the place the text stops being JSON and what its first line
    // reads (the parser's "expected ident" was all it said of a table).
    for (name, text, reads) in [
        ("frames.csv", "v0,v1\n1,2\n", "\"v0,v1\""),
        ("f.csv", "f0,f1,f2\n1,2,3\n", "\"f0,f1,f2\""),
        ("scene.toml", "[sheet]\nshape = 1\n", "\"[sheet]\""),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let e = Model::load(&path).unwrap_err().to_string();
        assert!(
            e.contains(&format!("{name}: not an et model file"))
                && e.contains("(line 1, column ")
                && e.contains(&format!(
                    "its first line reads {reads}: a file of another kind"
                )),
            "{e}"
        );
    }
    // A model edited in Python with a value past a float's range (json writes NaN and
    // Infinity, which are not JSON): said as that, by its place (it was "not an et model file
    // (et train writes JSON): expected value").
    for (token, text) in [
        (
            "NaN",
            "{\"format\": \"et-table-model\",\n \"feature_mean\": [1.0, NaN]}",
        ),
        (
            "-Infinity",
            "{\"format\": \"et-table-model\",\n \"feature_mean\": [-Infinity]}",
        ),
    ] {
        let path = dir.join("edited.json");
        std::fs::write(&path, text).unwrap();
        let e = Model::load(&path).unwrap_err().to_string();
        assert!(
            e.contains(&format!("edited.json: {token} at line 2, column "))
                && e.contains("not JSON, which has no NaN or infinity")
                && !e.contains("not an et model file"),
            "{e}"
        );
    }
    // A dataset or a recording given as the model: said as what it is and where it goes (a
    // recording was "trailing characters (line 2, column 1)", a dataset "expected value").
    for (name, text, said) in [
        (
            "d.csv",
            "# et-dataset 2\n# config: {}\nlabel,f0\n",
            "d.csv: an et dataset (et collect), not a model file: give it as --data",
        ),
        (
            "r.jsonl",
            "{\"format\":\"et-recording\",\"version\":1}\n{\"seq\":0}\n",
            "r.jsonl: an et recording (et sim, et record), not a model file: `et stream --replay",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let e = Model::load(&path).unwrap_err().to_string();
        assert!(e.contains(said), "{e}");
    }
    // JSON that goes wrong later is said by its place alone.
    std::fs::write(dir.join("late.json"), "{\"format\": x}").unwrap();
    let e = Model::load(&dir.join("late.json")).unwrap_err().to_string();
    assert!(!e.contains("first line"), "{e}");
    let e = Model::load(&dir.join("missing.json")).unwrap_err();
    assert!(matches!(e, ModelError::Io { .. }), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
