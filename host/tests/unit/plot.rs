use et_host::plot::*;
use plotters::prelude::*;
use std::path::Path;

/// A PNG's size and RGB pixels.
fn pixels(path: &Path) -> (u32, u32, Vec<u8>) {
    read_png(path).expect("a PNG")
}

#[test]
fn charts_and_heat_maps_are_real_pngs_with_what_was_drawn() {
    let dir = std::env::temp_dir().join(format!("et-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let line = dir.join("line.png");
    chart(
        &line,
        Labels {
            title: "learning curve",
            x: "n_c",
            y: "accuracy (%)",
            legend: Legend::UpperLeft,
        },
        &[Series {
            label: "QDA".into(),
            points: vec![(10.0, 50.0), (100.0, 90.0), (f64::NAN, 1.0)],
            scatter: false,
        }],
    )
    .unwrap();
    let (w, h, px) = pixels(&line);
    assert_eq!((w, h), (800, 520));
    // The first series' colour is on the canvas.
    assert!(px.chunks(3).any(|p| p == [31, 119, 180]));
    let map = dir.join("map.png");
    heatmap(
        &map,
        Labels {
            title: "t",
            x: "predicted",
            y: "true",
            legend: Legend::UpperLeft,
        },
        &[0.0, 1.0, 0.5, f64::INFINITY],
        (2, 2),
        (0.0, 1.0),
        "fraction",
    )
    .unwrap();
    let (w, _, px) = pixels(&map);
    assert_eq!(w, 780);
    // Both ends of the colour map and the grey of the non-finite cell appear.
    for colour in [viridis(0.0), viridis(1.0), RGBColor(160, 160, 160)] {
        assert!(
            px.chunks(3).any(|p| p == [colour.0, colour.1, colour.2]),
            "{colour:?}"
        );
    }
    assert!(
        heatmap(
            &map,
            Labels {
                title: "",
                x: "",
                y: "",
                legend: Legend::UpperLeft,
            },
            &[1.0],
            (2, 2),
            (0.0, 1.0),
            ""
        )
        .is_err()
    );
    let bad = dir.join("no-such-dir").join("x.png");
    let e = chart(
        &bad,
        Labels {
            title: "",
            x: "",
            y: "",
            legend: Legend::UpperLeft,
        },
        &[],
    )
    .unwrap_err();
    assert!(e.to_string().contains("no-such-dir"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn ticks_are_round_inside_the_range_and_labelled_without_minus_zero() {
    let t = nice_ticks(-62.5, 62.5, 6);
    assert_eq!(t, [-60.0, -40.0, -20.0, 0.0, 20.0, 40.0, 60.0]);
    let label = axis_labels(-62.5, 62.5);
    let labels: Vec<String> = t.iter().map(&label).collect();
    assert_eq!(labels[3], "0");
    assert_eq!(labels[0], "-60");
    let t = nice_ticks(-0.37, 0.37, 4);
    assert_eq!(t, [-0.2, 0.0, 0.2]);
    let label = axis_labels(-0.37, 0.37);
    assert_eq!(label(&-1e-17), "0");
    assert_eq!(label(&0.4), "0.4");
    assert!(nice_ticks(1.0, 1.0, 5).is_empty());
    assert!(nice_ticks(f64::NAN, 1.0, 5).is_empty());
}

#[test]
fn the_diverging_map_is_white_at_zero_and_opposite_at_the_ends() {
    assert_eq!(diverging(0.5), RGBColor(247, 247, 247));
    let (lo, hi) = (diverging(0.0), diverging(1.0));
    assert!(lo.2 > lo.0, "blue below zero: {lo:?}");
    assert!(hi.0 > hi.2, "red above zero: {hi:?}");
    assert_eq!(diverging(-3.0), lo);
    assert_eq!(diverging(f64::NAN), diverging(0.5));
}

#[test]
fn axis_labels_need_no_more_decimals_than_the_span_and_no_minus_zero() {
    let seconds = axis_labels(0.0, 0.22);
    let labels: Vec<String> = [0.0, 0.05, 0.1, 0.15, 0.2].iter().map(&seconds).collect();
    assert_eq!(labels, ["0", "0.05", "0.1", "0.15", "0.2"]);
    let triangles = axis_labels(1000.0, 16200.0);
    assert_eq!(triangles(&2000.0), "2000");
    let mm = axis_labels(-110.0, 110.0);
    assert_eq!(mm(&-1e-13), "0");
    assert_eq!(mm(&-20.0), "-20");
}
