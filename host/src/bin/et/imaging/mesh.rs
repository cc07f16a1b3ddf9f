//! The mesh a command images or simulates on: an imported one, or the scene's sheet meshed to
//! a count of triangles and refined where asked.

use anyhow::{Context, Result, bail};
use et_sim::scene::Scene;

use super::MeshArgs;

/// The mesh plan of a command: `--mesh` (Gmsh `.msh`, or three CSV files separated by commas)
/// or the scene's sheet meshed to about `--triangles`, refined at `--refine` (and at the
/// scene's touches when `at_touches`).
pub(super) fn mesh_plan(
    scene: &Scene,
    args: &MeshArgs,
    at_touches: bool,
) -> Result<et_recon::MeshPlan> {
    use et_recon::MeshPlan;
    use et_recon::mesh::{Mesh, Refinement};
    let mut refine = Vec::new();
    for r in &args.refine {
        let v: Vec<f64> = r
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()
            .filter(|v: &Vec<f64>| v.len() == 3)
            .with_context(|| {
                format!("--refine '{r}': three numbers X,Y,R in mm, e.g. 20,-15,12")
            })?;
        // (Said in the flag's mm: the mesh's check said "centre (0, 0) m, radius 0 m".)
        if !(v.iter().all(|x| x.is_finite()) && v[2] > 0.0) {
            bail!(
                "--refine '{r}': a finite centre X,Y and a radius R above 0, in mm (e.g. 20,-15,12)"
            );
        }
        let region = Refinement {
            centre: [v[0] * 1e-3, v[1] * 1e-3],
            radius: v[2] * 1e-3,
            edge: v[2] * 1e-3 / 6.0,
        };
        // A region whose edges are no finer than the mesh's own refines nothing (`0,0,1000`
        // on a 0.1 m disc was taken without a word).
        let h = et_recon::mesh::MeshSize::for_count(&scene.sheet.physical, args.triangles).interior;
        if args.mesh.is_none() && region.edge >= h {
            bail!(
                "--refine '{r}': edges of R/6 = {:.3} mm inside, no finer than the mesh's own \
                 {:.3} mm at --triangles {}: it refines nothing; give R under {:.1} mm, or \
                 more triangles",
                region.edge * 1e3,
                h * 1e3,
                args.triangles,
                6.0 * h * 1e3
            );
        }
        refine.push(region);
    }
    if at_touches {
        refine.extend(
            scene
                .touches
                .iter()
                .map(|t| Refinement::touch(t.position, t.radius)),
        );
    }
    if args.mesh.is_some() && !args.refine.is_empty() {
        bail!("--refine meshes the scene's sheet; it cannot change an imported --mesh");
    }
    Ok(match args.mesh.as_deref() {
        None => MeshPlan::About {
            triangles: args.triangles,
            refine,
        },
        Some(f) => MeshPlan::Given(match f.split(',').collect::<Vec<_>>()[..] {
            [one] => Mesh::from_gmsh(std::path::Path::new(one))?,
            [n, t, e] => Mesh::from_csv(n.as_ref(), t.as_ref(), e.as_ref())?,
            _ => bail!("--mesh '{f}': {}", et_recon::mesh::import::MESH_FILES),
        }),
    })
}
