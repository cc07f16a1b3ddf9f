//! `et protocol`: a protocol's tables for people and programs, and a protocol file crossed
//! from a system's lists of injections and measurements.

use std::path::PathBuf;

use anyhow::{Result, bail};
use et_core::protocol::{Pattern, Protocol, ProtocolKind, SkipSet};
use et_host::pairs::{self, By, Crossing};
use et_host::tables::ProtocolTables;

/// How a matrix's patterns lie (`--patterns`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Lie {
    /// A pattern a row (EIDORS's meas_pattern; a CSV of one pattern a line).
    Rows,
    /// A pattern a column (KIT4's and the Kuopio challenge's Injref and Mpat).
    Columns,
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("lists").args(["injections", "stimulation"])))]
pub(crate) struct ProtocolArgs {
    /// Electrode count L: even, 4 to 32 [default: 16; with --injections or --stimulation,
    /// the files'].
    #[arg(short = 'l', long,
          value_parser = crate::domain::whole(et_core::protocol::L_MIN, et_core::protocol::L_MAX))]
    electrodes: Option<u8>,
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
    /// With --csv, --injections or --stimulation: the current of every row, A (1e-9, a
    /// board's least, to 0.05: more is a unit slip) [default: 1e-3, or the files'].
    #[arg(long,
          value_parser = crate::domain::real(et_core::schedule::MIN_CURRENT_A,
                                             et_core::schedule::MAX_CURRENT_A))]
    current_a: Option<f64>,
    /// A system's injections, to cross with --measurements into a protocol file (printed as
    /// --csv prints one): a list of pairs (a row each: source, sink and optionally its
    /// current, named in a header or in that order; KIT4's and the Kuopio challenge's
    /// injection_pairs.csv) or a matrix of current patterns (+I at the
    /// source, -I at the sink, 0 elsewhere: injections.csv, Injref, EIDORS's stim_pattern),
    /// as a CSV, .npy, .npz:NAME or .mat:VARIABLE. Every measurement is taken under every
    /// injection, injection by injection, as those systems' frames are.
    #[arg(long, requires = "measurements", value_name = "FILE",
          conflicts_with_all = ["protocol", "drive_skip", "measure_skip", "json"])]
    injections: Option<PathBuf>,
    /// The measurements under each injection, with --injections: a list of pairs (positive,
    /// negative: the value is U_positive - U_negative; measurement_pairs.csv) or a matrix of
    /// patterns (+1 and -1: Mpat, EIDORS's meas_pattern).
    #[arg(long, requires = "injections", value_name = "FILE")]
    measurements: Option<PathBuf>,
    /// EIDORS's protocol, printed as a protocol file: the struct array mk_stim_patterns
    /// returns (a forward model's stimulation), saved in a .mat (`save stim.mat stim`; name
    /// one of several as stim.mat:stim, or a model's as model.mat:fmdl.stimulation). Each
    /// element is an injection (its stim_pattern) with its own measurements (its
    /// meas_pattern's rows), in EIDORS's order, rotate_meas and no_redundant included.
    #[arg(long, value_name = "FILE.mat[:NAME]",
          conflicts_with_all = ["protocol", "drive_skip", "measure_skip", "json", "injections",
                                "measurements", "patterns"])]
    stimulation: Option<PathBuf>,
    /// With --injections or --stimulation: what the lists count electrodes from, 0 or 1
    /// [default: 0 where a list holds an electrode 0, else 1]. The protocol file keeps the
    /// lists' numbering; patterns' electrodes are written from 0 (--base 1: from 1, as
    /// MATLAB counts them).
    #[arg(long, requires = "lists", value_parser = crate::domain::whole(0u16, 1u16))]
    base: Option<u16>,
    /// With --injections or --stimulation: the unit of the file's currents, where its
    /// column's name does not say it (`amplitude`; KIT4's and the Kuopio challenge's are
    /// mA; patterns' are A unless given): A, mA, uA or nA.
    #[arg(long, requires = "lists", conflicts_with = "current_a", value_parser = current_unit)]
    current_unit: Option<(String, f64)>,
    /// With --injections: how a square matrix whose rows and columns both read as patterns
    /// holds them (asked for only then).
    #[arg(long, requires = "injections", value_enum, ignore_case = true)]
    patterns: Option<Lie>,
    /// With --injections or --stimulation: leave out each injection's measurements on its
    /// own drive electrodes, as EIDORS's no_meas_current (they carry the contact's impedance).
    #[arg(long, requires = "lists")]
    no_meas_current: bool,
}

/// `--current-unit`: a unit of current, as named and in amperes.
fn current_unit(text: &str) -> Result<(String, f64), String> {
    pairs::amperes_per(text)
        .map(|per| (text.trim().to_string(), per))
        .ok_or_else(|| format!("'{text}' is not a unit of current: give A, mA, uA or nA"))
}

/// Prints the protocol file crossed from `--injections` and `--measurements`, or read from
/// `--stimulation`; what was read and done to standard error.
fn crossed(args: &ProtocolArgs) -> Result<()> {
    let crossing = Crossing {
        electrodes: args.electrodes.map(u16::from),
        base: args.base,
        current_a: args.current_a,
        current_unit: args.current_unit.clone(),
        by: args.patterns.map(|p| match p {
            Lie::Rows => By::Rows,
            Lie::Columns => By::Columns,
        }),
        no_meas_current: args.no_meas_current,
    };
    let crossed = match (&args.stimulation, &args.injections, &args.measurements) {
        (Some(stimulation), _, _) => pairs::stimulation(stimulation, &crossing)?,
        (None, Some(injections), Some(measurements)) => {
            pairs::cross(injections, measurements, &crossing)?
        }
        _ => bail!("--injections needs --measurements"),
    };
    for line in &crossed.said {
        say!("{line}");
    }
    out!("{}", crossed.to_csv().trim_end());
    Ok(())
}

pub(crate) fn run(args: &ProtocolArgs) -> Result<()> {
    if args.injections.is_some() || args.stimulation.is_some() {
        return crossed(args);
    }
    if args.current_a.is_some() && !args.csv {
        bail!(
            "--current-a is the current of --csv's rows, or of --injections' or \
             --stimulation's: give it with one"
        );
    }
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
    let protocol = Protocol::new(kind, args.electrodes.unwrap_or(16))?;
    if args.csv {
        let current_a = args.current_a.unwrap_or(1e-3);
        out!("{}", protocol.schedule(current_a)?.to_csv().trim_end());
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
