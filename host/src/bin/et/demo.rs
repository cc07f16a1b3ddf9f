//! `et demo`: the whole method on the simulated sheet into a report folder.

use std::path::PathBuf;

use anyhow::Result;

#[derive(Debug, clap::Args)]
pub(crate) struct DemoArgs {
    /// The report folder (created; an existing report is replaced only with --force).
    #[arg(long, default_value = "et-demo-report")]
    out: PathBuf,
    /// Small sizes everywhere: checks the whole pipeline in seconds, numbers not to quote.
    #[arg(long)]
    quick: bool,
    /// Print the summary as JSON on stdout (progress stays on stderr).
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(args: &DemoArgs, force: bool) -> Result<()> {
    let command = std::iter::once("et".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    let report = et_host::demo::run(&et_host::demo::Options {
        out: args.out.clone(),
        quick: args.quick,
        force,
        progress: !args.json,
        command,
    })?;
    if args.json {
        out!("{}", report.summary);
    } else {
        say!("\nreport: {}", report.index.display());
    }
    Ok(())
}
