//! Calibrates the simulated front end's two noise layers to the reference hardware and prints
//! the fitted parameters with what they give (docs/calibration.md, `et_sim::calibration`).
//!
//! On the 13 x 13 cm, 16-electrode sheet, untouched, adjacent protocol at the reference scan
//! settings and PGIA gain 8:
//!
//! - frame to frame: SNR 55 dB at 32 uA and 49 dB at 10 uA (per channel over repeated frames,
//!   averaged over channels), fitted by the white noise per sample and the current jitter the
//!   readings see (the ADC's 0.5 code and 10 uV of hum fixed);
//! - between measurement sets: MAD 0.5 mV at 32 uA and 0.4 mV at 10 uA (each set's mean frame
//!   against the mean over sets), fitted by each electrode's junction potential and the
//!   sheet's conductance, the sheet staying mounted between sets (`--movement-mm M`: its
//!   clips put back M mm rms off between sets instead; default `CALIBRATION_MOVEMENT_M`, 0).
//!
//! Run: `cargo run --release -p et-sim --example calibrate [-- --movement-mm 0]`

use std::sync::Arc;

use et_sim::calibration::{
    MAD_V, SNR_DB, fit_frame_layer, fit_set_layer, frame_snr, replaced_sheets, set_mad, sheet_spec,
};
use et_sim::frontend::{FrontendSpec, SetSpread};
use et_sim::sheet::SimulatedSheet;

const FRAMES: usize = 400;
const SETS: usize = 120;
const FRAMES_PER_SET: usize = 10;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let movement = match args.iter().position(|a| a == "--movement-mm") {
        Some(i) => {
            args.get(i + 1)
                .ok_or("--movement-mm needs a value")?
                .parse::<f64>()?
                * 1e-3
        }
        None => et_sim::frontend::CALIBRATION_MOVEMENT_M,
    };
    let spec = sheet_spec();
    let sheet = Arc::new(SimulatedSheet::new(&spec, &[])?);
    let defaults = FrontendSpec::default();
    let sets = replaced_sheets(&spec, movement, SETS, 5)?;
    let show = |name: &str, fe: FrontendSpec| -> Result<(), Box<dyn std::error::Error>> {
        println!(
            "{name}: white noise {:.1} uV, current jitter {:.3} %, junction potential {:.1} uV, conductance {:.2} %",
            fe.white_noise_v * 1e6,
            fe.current_noise * 100.0,
            fe.sets.contact_potential_v * 1e6,
            fe.sets.conductance * 100.0
        );
        for ((na, db), (_, v)) in SNR_DB.iter().zip(MAD_V) {
            println!(
                "  {:>2} uA: SNR {:.2} dB (reference {db}), MAD between sets {:.3} mV (reference {})",
                na / 1000,
                frame_snr(&sheet, fe, *na, FRAMES, 42)?,
                set_mad(&sets, fe, *na, FRAMES_PER_SET, 1_000)? * 1e3,
                v * 1e3
            );
        }
        Ok(())
    };
    show("defaults", defaults)?;
    let none = FrontendSpec {
        sets: SetSpread {
            contact_potential_v: 0.0,
            conductance: 0.0,
        },
        ..defaults
    };
    for ((na, _), _) in SNR_DB.iter().zip(MAD_V) {
        println!(
            "  re-placement alone ({:.2} mm rms) at {:>2} uA: MAD {:.3} mV",
            movement * 1e3,
            na / 1000,
            set_mad(&sets, none, *na, FRAMES_PER_SET, 1_000)? * 1e3
        );
    }
    let frame = fit_frame_layer(&sheet, defaults, FRAMES)?;
    let fitted = fit_set_layer(&sets, frame, FRAMES_PER_SET)?;
    show("fitted", fitted)?;
    Ok(())
}
