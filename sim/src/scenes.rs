//! The scenes compiled into et (`scenes/*.toml`, embedded once, here): the default sheet that
//! `et sim`, `et stream`, the viewer, the demo and the QEMU image's sheet start from, and the
//! reference scenarios the demo images. Each is (file name, TOML text).

/// The default sheet (docs/method.md §1): 13 x 13 cm, 16 electrodes.
pub const DEFAULT_SCENE: (&str, &str) = (
    "square-13cm-16.toml",
    include_str!("../scenes/square-13cm-16.toml"),
);

/// docs/method.md §7's reference scenarios: 22 cm disc, one target at x = 0.75, 0.5, 0.25, 0 of
/// the radius, and two at x = -0.5 and 0.5.
pub const REFERENCE_SCENES: [(&str, &str); 5] = [
    (
        "disc-ref-x075.toml",
        include_str!("../scenes/disc-ref-x075.toml"),
    ),
    (
        "disc-ref-x050.toml",
        include_str!("../scenes/disc-ref-x050.toml"),
    ),
    (
        "disc-ref-x025.toml",
        include_str!("../scenes/disc-ref-x025.toml"),
    ),
    (
        "disc-ref-x000.toml",
        include_str!("../scenes/disc-ref-x000.toml"),
    ),
    (
        "disc-ref-two.toml",
        include_str!("../scenes/disc-ref-two.toml"),
    ),
];
