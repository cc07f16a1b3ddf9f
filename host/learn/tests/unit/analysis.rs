use et_learn::analysis::*;

#[test]
fn distance_bands_count_and_average() {
    let e = [[0.0, 0.0], [100.0, 0.0]];
    assert_eq!(electrode_distance([3.0, 4.0], &e), 5.0);
    assert_eq!(electrode_distance([97.0, 4.0], &e), 5.0);
    assert!(electrode_distance([1.0, 1.0], &[]).is_infinite());
    let o = |d: f64, err: f64| Outcome {
        distance_mm: d,
        error_mm: err,
    };
    let bands = by_distance(
        &[o(1.0, 0.0), o(9.0, 10.0), o(25.0, 0.0), o(26.0, 0.0)],
        10.0,
    );
    assert_eq!(bands.len(), 2, "the empty 10-20 mm band is left out");
    assert_eq!(
        (bands[0].count, bands[0].accuracy, bands[0].mean_error_mm),
        (2, 0.5, 5.0)
    );
    assert_eq!(
        (bands[1].from_mm, bands[1].count, bands[1].accuracy),
        (20.0, 2, 1.0)
    );
}

#[test]
fn subsets_keep_n_c_per_class_across_the_whole_class() {
    let y: Vec<u16> = (0..30).map(|i| (i % 3) as u16).collect();
    let rows = per_class_subset(&y, 3, 4);
    assert_eq!(rows.len(), 12);
    for c in 0..3u16 {
        let mine: Vec<usize> = rows.iter().copied().filter(|&r| y[r] == c).collect();
        assert_eq!(mine.len(), 4);
        // Spread over the class (first and second half both represented).
        assert!(mine.iter().any(|&r| r < 15) && mine.iter().any(|&r| r >= 15));
    }
    assert_eq!(
        per_class_subset(&y, 3, 100).len(),
        30,
        "capped at what there is"
    );
}
