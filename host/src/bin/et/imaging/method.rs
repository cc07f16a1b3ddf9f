//! The reconstruction method and its alpha rule as `et reconstruct`'s flags ask for them,
//! one method's flags beside the other refused.

use anyhow::{Result, bail};
use et_recon::Method;

use super::ReconstructArgs;

/// The NOSER exponent unless `--s` gives another.
pub(super) const NOSER_S: f64 = 0.5;

/// The reconstruction `et reconstruct`'s arguments ask for.
pub(super) fn method_and_alpha(
    args: &ReconstructArgs,
) -> Result<(et_recon::Method, et_recon::AlphaRule)> {
    use et_recon::AlphaRule;
    // A flag of the other method changes nothing: refused, not ignored.
    let method = match args.method {
        Method::Greit { .. } => {
            if args.iterations > 1 {
                bail!(
                    "--iterations {} is for --method gn: GREIT is one matrix",
                    args.iterations
                );
            }
            if let Some(s) = args.s {
                bail!("--s {s} is Gauss-Newton's NOSER exponent: GREIT has no prior (drop it)");
            }
            if let Some(nf) = args.noise_figure
                && args.alpha != "auto"
            {
                bail!(
                    "--noise-figure {nf} sets GREIT's lambda under --alpha auto; --alpha {} \
                     sets it otherwise: give one of them",
                    args.alpha
                );
            }
            Method::Greit {
                radius: args.radius_mm.map(|r| r * 1e-3),
            }
        }
        Method::GaussNewton { .. } => {
            if args.noise_figure.is_some() || args.radius_mm.is_some() {
                bail!(
                    "--noise-figure and --radius-mm are GREIT's (--method greit); Gauss-Newton's \
                     smoothing is --alpha and --s"
                );
            }
            Method::GaussNewton {
                s: args.s.unwrap_or(NOSER_S),
                iterations: args.iterations,
            }
        }
    };
    let noise_figure = args.noise_figure.unwrap_or(et_recon::greit::NOISE_FIGURE);
    let alpha = AlphaRule::from_text(&args.alpha, &method, noise_figure).map_err(|_| {
        anyhow::anyhow!(
            "--alpha '{}': a number, auto, corner, gcv, discrepancy, lcurve or quasi-optimality",
            args.alpha
        )
    })?;
    Ok((method, alpha))
}
