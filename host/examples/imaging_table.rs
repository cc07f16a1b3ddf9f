//! The speed/accuracy table of imaging: mesh size against forward error, position error (PE)
//! and set-up time; one-step against iterative Gauss-Newton. 22 cm disc, 16 electrodes,
//! adjacent protocol, complete electrode model; the touch is docs/method.md §7's at x = 0.5 (noiseless
//! frames from the simulator's resistor network, so the reconstruction never sees its own
//! model's data). The same sweep as `et demo`'s, at larger sizes (reference mesh 128 000
//! triangles, meshes up to 32 000).
//!
//! Run: `cargo run --release -p et-host --example imaging_table`

fn main() -> anyhow::Result<()> {
    let reference = 128_000;
    println!("Reference: a mesh of about {reference} triangles.\n");
    println!(
        "| triangles | forward error | set-up (mesh + Jacobian + one-step matrix) | live frame | PE one-step | iterative GN, 4 steps: PE, time |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    et_host::demo::mesh_sweep(
        &[1_000, 2_000, 4_000, 8_000, 16_000, 32_000],
        reference,
        8_500,
        |r| {
            println!(
                "| {} | {:.2} % | {:.3} s | {:.0} us | {:.3} | {} |",
                r.triangles,
                100.0 * r.forward_error,
                r.setup_s,
                r.live_frame_us,
                r.pe_one_step,
                r.iterative
                    .map_or("-".into(), |(pe, t)| format!("{pe:.3}, {t:.2} s"))
            );
        },
    )?;
    Ok(())
}
