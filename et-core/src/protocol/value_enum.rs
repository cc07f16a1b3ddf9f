//! The named protocols as command-line values (clap's `ValueEnum`, feature `clap`).

use super::ProtocolKind;

/// The four named protocols as command-line values, with their short names as aliases.
impl clap::ValueEnum for ProtocolKind {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::NAMED
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        use clap::builder::PossibleValue;
        Some(match self {
            ProtocolKind::Adjacent => PossibleValue::new("adjacent").alias("ad").help(
                "AD: inject and measure between neighbouring electrodes (most sensitive near \
                 the edge)",
            ),
            ProtocolKind::PseudoPolar => PossibleValue::new("pseudo-polar")
                .aliases(["pp", "pseudopolar"])
                .help("PP: inject between electrodes one short of opposite, measure between neighbours"),
            ProtocolKind::PpPp => PossibleValue::new("pp-pp").alias("pppp").help(
                "PP-PP: inject one short of opposite; measure between neighbours and one short \
                 of opposite",
            ),
            ProtocolKind::Opposite => PossibleValue::new("opposite")
                .aliases(["polar", "op"])
                .help(
                    "Inject between opposite electrodes, measure between neighbours (most \
                     sensitive in the middle)",
                ),
            ProtocolKind::Custom(_) => return None,
        })
    }
}
