//! `et protocol`: a protocol's tables for people and programs.

use anyhow::{Result, bail};
use et_core::protocol::{Pattern, Protocol, ProtocolKind, SkipSet};
use et_host::tables::ProtocolTables;

#[derive(Debug, clap::Args)]
pub(crate) struct ProtocolArgs {
    /// Electrode count L: even, 4 to 32.
    #[arg(short = 'l', long, default_value_t = 16,
          value_parser = crate::domain::whole(et_core::protocol::L_MIN, et_core::protocol::L_MAX))]
    electrodes: u8,
    /// The protocol (docs/method.md §4); the general form (--drive-skip) is another.
    #[arg(short, long, value_enum, ignore_case = true, default_value_t = ProtocolKind::Adjacent)]
    protocol: ProtocolKind,
    /// General form: inject between i and i + drive_skip + 1 (needs --measure-skip).
    #[arg(long, requires = "measure_skip", conflicts_with = "protocol",
          value_parser = crate::domain::whole(0, u8::MAX))]
    drive_skip: Option<u8>,
    /// General form: measure between j and j + s + 1; give once or twice.
    #[arg(long, value_parser = crate::domain::whole(0, u8::MAX))]
    measure_skip: Vec<u8>,
    /// Print JSON (all tables, machine-readable) instead of text.
    #[arg(long, conflicts_with = "csv")]
    json: bool,
    /// Print the protocol as a protocol file: one row per frame value, source, sink,
    /// positive, negative (electrodes from 0) and current_a; a scene takes it as
    /// `[scan] protocol = { file = "protocol.csv" }`. Edit it into your own system's.
    #[arg(long)]
    csv: bool,
    /// With --csv: the current of every row, A (1e-9, a board's least, to 0.05: more is a
    /// unit slip).
    #[arg(long, default_value_t = 1e-3, requires = "csv",
          value_parser = crate::domain::real(et_core::schedule::MIN_CURRENT_A,
                                             et_core::schedule::MAX_CURRENT_A))]
    current_a: f64,
}

pub(crate) fn run(args: &ProtocolArgs) -> Result<()> {
    let kind = match args.drive_skip {
        Some(drive_skip) => {
            let mut skips = SkipSet(0);
            for &s in &args.measure_skip {
                if s >= 32 {
                    bail!("--measure-skip {s} is too large: use a skip below L/2");
                }
                skips = skips.with(s);
            }
            ProtocolKind::Custom(Pattern {
                drive_skip,
                measure_skips: skips,
            })
        }
        None => {
            if !args.measure_skip.is_empty() {
                bail!("--measure-skip needs --drive-skip (the general form)");
            }
            args.protocol
        }
    };
    let protocol = Protocol::new(kind, args.electrodes)?;
    if args.csv {
        out!("{}", protocol.schedule(args.current_a)?.to_csv().trim_end());
        return Ok(());
    }
    let tables = ProtocolTables::new(&protocol);
    if args.json {
        out!("{}", serde_json::to_string_pretty(&tables)?);
    } else {
        out!("{}", tables.to_text().trim_end_matches('\n'));
    }
    Ok(())
}
