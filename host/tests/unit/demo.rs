use et_core::board::MODEL_SLOT_BYTES;
use et_host::demo::report::civil_date;
use et_host::demo::*;

#[test]
fn civil_dates_match_the_calendar() {
    // Day counts from Python's datetime.date(...) - date(1970, 1, 1).
    assert_eq!(civil_date(0), "1970-01-01");
    assert_eq!(civil_date(11_016), "2000-02-29");
    assert_eq!(civil_date(20_780), "2026-11-23");
    // 2100 is not a leap year: 28 February is followed by 1 March.
    assert_eq!(civil_date(47_541), "2100-03-01");
    assert_eq!(civil_date(47_540), "2100-02-28");
}

/// The quick demo end to end: every figure the page shows exists and is a real PNG, the
/// summary on disk is the one returned, and the numbers in it are what the pipeline must
/// deliver even at small sizes.
#[test]
fn the_quick_demo_writes_a_complete_report() {
    let dir = std::env::temp_dir().join(format!("et-demo-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let report = run(&Options {
        out: dir.clone(),
        quick: true,
        force: false,
        progress: false,
        command: "et demo --quick".into(),
    })
    .unwrap();
    assert_eq!(report.index, dir.join("index.md"));
    // An older report is not overwritten without being asked (it is refused before any work).
    let again = run(&Options {
        out: dir.clone(),
        quick: true,
        force: false,
        progress: false,
        command: "et demo --quick".into(),
    });
    let e = format!("{:#}", again.expect_err("refused"));
    assert!(e.contains("already exists") && e.contains("--force"), "{e}");
    assert!(report.index.exists(), "the old report is left alone");
    let page = std::fs::read_to_string(&report.index).unwrap();
    let figures: Vec<&str> = page
        .split("![")
        .skip(1)
        .filter_map(|s| {
            let start = s.find("](")? + 2;
            Some(&s[start..start + s[start..].find(')')?])
        })
        .collect();
    // 5 scenes x 4 protocols, 4 learning figures, 3 sweep figures.
    assert_eq!(figures.len(), 27, "{figures:?}");
    for f in &figures {
        let (width, height, px) =
            et_host::plot::read_png(&dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(width >= 600 && height >= 400, "{f}");
        // Every image of the sheet shows the truth (green circles) and the ROI's outline
        // (black), over a map white at zero.
        if f.starts_with("imaging/") {
            for colour in [[0u8, 150, 80], [0, 0, 0], [247, 247, 247]] {
                assert!(
                    px.chunks_exact(3).any(|p| p == colour),
                    "{f}: no pixel of {colour:?}"
                );
            }
        }
    }
    // Each figure is explained, and the report ends with its glossary.
    assert!(page.matches("How to read this").count() >= 7, "{page}");
    assert!(page.contains("## Glossary") && page.contains("| NOSER |"));
    let on_disk: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    // The file is the summary returned (floats printed to 17 digits may differ in the last).
    let keys = |v: &serde_json::Value| v.as_object().map(|o| o.keys().cloned().collect::<Vec<_>>());
    assert_eq!(keys(&on_disk), keys(&report.summary));
    assert_eq!(
        on_disk["learning"]["chip"],
        report.summary["learning"]["chip"]
    );

    let l = &on_disk["learning"];
    // 49 classes (chance 2 %) from 2 visits of 2 scans on the calibrated simulator: far above
    // chance (the full demo's larger training set is what the README reports).
    let acc = l["qda"]["next_day_accuracy"].as_f64().unwrap();
    assert!(acc > 0.5, "next-day accuracy {acc}");
    // The chip's blob parses in et-core and decides as the host model does.
    let blob = std::fs::read(dir.join("learning/model.etm")).unwrap();
    assert!(et_core::model::Model::parse(&blob).is_ok());
    assert!(blob.len() <= MODEL_SLOT_BYTES);
    let chip = &l["chip"];
    let (total, disagree) = (
        chip["total"].as_u64().unwrap(),
        chip["disagree_with_host"].as_u64().unwrap(),
    );
    assert!(total > 0 && disagree * 100 <= total, "{chip}");

    let images = on_disk["imaging"]["images"].as_array().unwrap();
    assert_eq!(images.len(), 20);
    for im in images {
        for m in ["pe", "se", "rng", "bvc"] {
            let v = im["metrics"][m].as_f64().unwrap();
            assert!(v.is_finite() && v >= 0.0, "{im}");
        }
    }
    // The x = 0.75 target, imaged with adjacent (the protocol for a touch near the
    // boundary, docs/method.md §8), is found within its radius.
    let near = images
        .iter()
        .find(|im| im["scene"] == "disc-ref-x075" && im["protocol"] == "adjacent")
        .unwrap();
    assert_eq!(near["found_within_radius"][0], true, "{near}");
    // The two touches, imaged with PP-PP: each true touch matched to its own found touch,
    // with its own PE.
    let two = images
        .iter()
        .find(|im| im["scene"] == "disc-ref-two" && im["protocol"] == "pp-pp")
        .unwrap();
    let m = two["touch_matches"].as_array().unwrap();
    assert_eq!(m.len(), 2, "{two}");
    assert!(m.iter().all(|t| t["pe"].as_f64().unwrap() < 0.1), "{two}");
    assert_ne!(m[0]["found"], m[1]["found"], "{two}");

    // Every single touch is found within its radius by the protocol docs/method.md §8 picks for it
    // from the adjacent image (adjacent near the edge, pseudo-polar towards the centre).
    let chosen = &on_disk["imaging"]["single_touches_found_with_chosen_protocol"];
    assert_eq!(chosen, &serde_json::json!([4, 4]));
    let rows = on_disk["sweep"]["rows"].as_array().unwrap();
    assert_eq!(rows.len(), QUICK_SWEEP.len());
    for r in rows {
        let live = r["live_frame_us"].as_f64().unwrap();
        let err = r["forward_error"].as_f64().unwrap();
        assert!(
            live > 0.0 && live.is_finite() && err.is_finite() && err < 0.1,
            "{r}"
        );
    }
    // The iterative Gauss-Newton ran on the smallest mesh and found the target.
    let pe_it = rows[0]["iterative"][0].as_f64().unwrap();
    assert!(pe_it < 0.1, "{}", rows[0]);
    std::fs::remove_dir_all(&dir).unwrap();
}
