//! Writes the stand-in e-skin data set (`et_learn::standin`) in its foreign format:
//! `features.csv` (n x 192, board units) and `targets.csv` (x, y, z in metres), both with a
//! byte-order mark and no header, for trying `et train --features` and for the comparison
//! with scikit-learn on the same rows.
//!
//! Usage: cargo run --release -p et-learn --example standin -- DIR [ROWS] [SESSIONS] [SEED]
//! [drifting] (defaults: 2500 rows over 5 sessions, seed 1; `drifting` adds per-channel gain
//! and offset changes between sessions, `standin::SessionDrift::SESSIONS`;
//! `drifting:GAIN,OFFSET` other standard deviations, e.g. `drifting:0.3,1` for sessions
//! further apart). Also writes
//! `sessions.csv`, each row's session, for `--groups`, and `pressed.csv` and `before.csv`, the
//! pressed frames and the frames before them, for `--reference-features`.

use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(
        args.next()
            .ok_or("usage: standin DIR [ROWS] [SESSIONS] [SEED]")?,
    );
    let rows: usize = args.next().map_or(Ok(2_500), |v| v.parse())?;
    let sessions: usize = args.next().map_or(Ok(5), |v| v.parse())?;
    let seed: u64 = args.next().map_or(Ok(1), |v| v.parse())?;
    let drift = match args.next().as_deref() {
        None => et_learn::standin::SessionDrift::NONE,
        Some("drifting") => et_learn::standin::SessionDrift::SESSIONS,
        Some(other) => match other
            .strip_prefix("drifting:")
            .and_then(|v| v.split_once(','))
            .and_then(|(g, o)| Some((g.parse().ok()?, o.parse().ok()?)))
        {
            Some((gain, offset)) => et_learn::standin::SessionDrift { gain, offset },
            None => {
                return Err(format!(
                    "'{other}': the fifth argument is 'drifting', 'drifting:GAIN,OFFSET' \
                     (e.g. drifting:0.3,1) or nothing"
                )
                .into());
            }
        },
    };
    std::fs::create_dir_all(&dir)?;
    let started = std::time::Instant::now();
    let data = et_learn::standin::make_drifting(rows, sessions, seed, drift)?;
    let (f, t) = (dir.join("features.csv"), dir.join("targets.csv"));
    data.write_all(&f, &t, Some(&dir.join("sessions.csv")))?;
    data.write_frames(&dir.join("pressed.csv"), &dir.join("before.csv"))?;
    eprintln!(
        "wrote {} and {} ({} rows x {} features, {sessions} sessions, seed {seed}) in {:.1} s",
        f.display(),
        t.display(),
        data.features.nrows(),
        data.features.ncols(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
