//! Long work's pace, said: `et_host::pace`.

use et_host::pace::Pace;

/// Short work says nothing; long work says its whole time once, at the pace so far, and
/// off a terminal each tenth it reaches, once.
#[test]
fn long_work_says_its_time_once_and_its_tenths() {
    let mut pace = Pace::new("simulate", "frames", 1000).on_terminal(false);
    assert!(pace.due(500, 2.9).is_empty());
    let first = pace.due(100, 4.0);
    assert_eq!(
        first,
        [
            "about 40 s to simulate in all, at the pace of its first 100 frames",
            "simulate: 10 % (100 of 1000 frames, 4.0 s)"
        ]
    );
    assert!(pace.due(150, 5.0).is_empty());
    assert_eq!(
        pace.due(420, 9.0),
        ["simulate: 40 % (420 of 1000 frames, 9.0 s)"]
    );
    // On a terminal the bar shows the tenths: only the whole's time is said.
    let mut drawn = Pace::new("collect", "presses", 10).on_terminal(true);
    assert_eq!(drawn.due(5, 3.0).len(), 1);
    assert!(drawn.due(10, 6.0).is_empty());
}
