use et_core::protocol::{Protocol, ProtocolKind};
use et_core::sheet::Sheet;
use et_recon::Imager;
use et_recon::fem::TransferJacobian;
use et_recon::greit::*;
use et_recon::mesh::Mesh;

/// The reference scenes' sheet: a 22 cm disc, 16 electrodes 6 mm wide.
fn small(kind: ProtocolKind) -> (Imager, TransferJacobian) {
    let mut sheet = Sheet::disc(0.11, 16);
    sheet.electrodes.width = 0.006;
    let mesh = Mesh::with_about(&sheet, 600).unwrap();
    let imager = Imager::new(&sheet, mesh, 24).unwrap();
    let protocol = Protocol::new(kind, 16).unwrap();
    let jac = imager
        .transfer_jacobian(&protocol.schedule(32e-6).unwrap())
        .unwrap();
    (imager, jac)
}

/// A triangle's desired image integrates to its area (the disc's ramp is one pixel wide
/// about the radius) wherever the disc lies inside the sheet.
#[test]
fn a_desired_image_integrates_to_its_triangle() {
    let (imager, _) = small(ProtocolKind::Adjacent);
    let grid = &imager.grid;
    let mesh = imager.forward.mesh();
    for radius in [0.01, 0.02, 0.04] {
        let (_, rows) = desired(grid, &imager, radius);
        let mut sums = vec![0.0; mesh.triangles.len()];
        for row in &rows {
            for &(t, w) in row {
                sums[t] += w * grid.size * grid.size;
            }
        }
        let mut checked = 0;
        for t in 0..mesh.triangles.len() {
            let c = mesh.centroid(t);
            // The 22 cm disc is centred at 0 with radius 0.11 m.
            if c[0].hypot(c[1]) + radius + grid.size < 0.11 {
                let area = 0.5 * mesh.double_area(t);
                let rel = (sums[t] - area).abs() / area;
                assert!(rel < 1e-12, "radius {radius}, triangle {t}: {rel}");
                checked += 1;
            }
        }
        assert!(checked > 10, "{checked}");
    }
}
