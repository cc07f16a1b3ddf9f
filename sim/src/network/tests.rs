//! Physics checks of the resistor network against identities and analytic references.

use super::*;

const RS: f64 = 30e3; // ohm per square

fn equally_spaced(l: usize) -> Vec<f64> {
    (0..l).map(|e| (e as f64 + 0.5) / l as f64).collect()
}

fn network(shape: &Shape, h: f64, l: usize, width: f64, z: f64) -> Network {
    let grid = Grid::new(shape, h);
    let contacts = place_contacts(shape, &grid, &equally_spaced(l), width, &vec![z; l], RS);
    Network::new(grid, contacts, 1.0 / RS).unwrap()
}

#[test]
fn reciprocity_holds_to_numerical_precision() {
    let shape = Shape::Rectangle {
        width: 0.13,
        height: 0.13,
    };
    let net = network(&shape, 0.004, 16, 0.006, 200.0);
    // A lumpy sheet, so that symmetry is not inherited from a symmetric geometry.
    let m: Vec<f64> = (0..net.grid.edges.len())
        .map(|k| 0.2 + ((k * 7919) % 97) as f64 / 20.0)
        .collect();
    let solved = net.solve(&net.conductances(Some(&m))).unwrap();
    let t = &solved.transfer;
    let scale = (0..16).map(|e| t.at(e, e)).fold(0.0, f64::max);
    for e in 0..16 {
        for f in 0..16 {
            assert!(
                (t.at(e, f) - t.at(f, e)).abs() <= 1e-10 * scale,
                "Z[{e}][{f}]"
            );
        }
    }
    // V(C,D | A,B) = V(A,B | C,D) through node potentials too.
    let (phi_ab, v_ab) = solved.potentials(2, 9, 1e-5);
    let (phi_cd, v_cd) = solved.potentials(5, 13, 1e-5);
    assert!(((v_ab[5] - v_ab[13]) - (v_cd[2] - v_cd[9])).abs() <= 1e-10 * scale * 1e-5);
    assert_eq!(phi_ab.len(), phi_cd.len());
}

#[test]
fn kirchhoff_current_balance_at_every_node_and_electrode() {
    let shape = Shape::Disc { radius: 0.11 };
    let net = network(&shape, 0.006, 16, 0.008, 500.0);
    let g = net.conductances(None);
    let solved = net.solve(&g).unwrap();
    let i = 32e-6;
    for (a, b) in [(1, 2), (0, 8), (7, 0), (3, 11)] {
        let (phi, v) = solved.potentials(a, b, i);
        // Net current leaving each node through its resistors and contacts.
        let mut out = vec![0.0; phi.len()];
        for (e, ge) in net.grid.edges.iter().zip(&g) {
            let (u, w) = (e.u as usize, e.v as usize);
            let c = ge * (phi[u] - phi[w]);
            out[u] += c;
            out[w] -= c;
        }
        let mut into_electrode = [0.0; 16];
        for (e, contact) in net.contacts.iter().enumerate() {
            for &(n, gc) in &contact.nodes {
                let c = gc * (phi[n as usize] - v[e]);
                out[n as usize] += c;
                into_electrode[e] += c;
            }
        }
        for (n, o) in out.iter().enumerate() {
            assert!(o.abs() <= 1e-9 * i, "node {n}: {o:e} A");
        }
        // Electrodes: +I drawn out at a (current enters the sheet there), -I at b, 0 elsewhere,
        // the grounded electrode 0 included.
        for (e, c) in into_electrode.iter().enumerate() {
            let want = if e == a {
                -i
            } else if e == b {
                i
            } else {
                0.0
            };
            assert!(
                (c - want).abs() <= 1e-9 * i,
                "electrode {e}: {c:e}, want {want:e}"
            );
        }
    }
}

#[test]
fn strip_resistance_is_exact() {
    // Full-side electrodes on a 20 x 10 cm strip: uniform current, R = R_s W / H + 2 z exactly,
    // at any resolution (the finite-volume weights make a uniform field exact).
    let shape = Shape::Rectangle {
        width: 0.2,
        height: 0.1,
    };
    for h in [0.02, 0.01, 0.0033] {
        let grid = Grid::new(&shape, h);
        let side = |x: f64| -> Vec<u32> {
            (0..grid.len() as u32)
                .filter(|&n| (grid.nodes[n as usize][0] - x).abs() < 1e-9)
                .collect()
        };
        let z = 150.0;
        let contact = |nodes: Vec<u32>| {
            // Conductance proportional to the face each boundary node owns (half at the corners).
            let hy = grid.spacing[1];
            let weights: Vec<f64> = nodes
                .iter()
                .map(|&n| {
                    if (grid.nodes[n as usize][1].abs() - 0.05).abs() < 1e-9 {
                        0.5 * hy
                    } else {
                        hy
                    }
                })
                .collect();
            let total: f64 = weights.iter().sum();
            Contact {
                nodes: nodes
                    .into_iter()
                    .zip(weights)
                    .map(|(n, w)| (n, w / total / z))
                    .collect(),
            }
        };
        let (left, right) = (contact(side(-0.1)), contact(side(0.1)));
        let net = Network::new(grid, vec![left, right], 1.0 / RS).unwrap();
        let t = net.solve(&net.conductances(None)).unwrap().transfer;
        let want = RS * 0.2 / 0.1 + 2.0 * z;
        assert!(
            (t.load(0, 1) - want).abs() < 1e-9 * want,
            "h={h}: {} vs {want}",
            t.load(0, 1)
        );
    }
}

/// Potential at x of unit current injected at y in a disc of radius R and sheet resistance
/// R_s with an insulating boundary (the Neumann Green's function, image charge at
/// R^2 y / |y|^2): G(x, y) = -(R_s / 2 pi) [ln|x - y| + ln| |y| x / R - R y / |y| |].
fn disc_green(x: [f64; 2], y: [f64; 2], r: f64) -> f64 {
    let ny = y[0].hypot(y[1]);
    let d = (x[0] - y[0]).hypot(x[1] - y[1]);
    let img = (ny * x[0] / r - r * y[0] / ny).hypot(ny * x[1] / r - r * y[1] / ny);
    -RS / (2.0 * std::f64::consts::PI) * (d.ln() + img.ln())
}

/// Relative RMS error of measured voltages against the analytic disc, for grid spacing h:
/// small electrodes (one node each), current between a few pairs, every adjacent measurement
/// pair away from the drive. The analytic model puts point sources and probes exactly at the
/// contact nodes, so what is measured is the network's discretisation error.
fn disc_error(h: f64) -> f64 {
    let (shape, r, l) = (Shape::Disc { radius: 0.11 }, 0.11, 16);
    // Point electrodes sitting exactly on edge nodes (one hat peaks there, the others vanish),
    // the edge node nearest each of 16 equally spaced angles.
    let grid = Grid::new(&shape, h);
    let layer = edge_layer(&shape, &grid);
    let perimeter = shape.perimeter();
    let positions: Vec<f64> = (0..l)
        .map(|e| {
            let want = (e as f64 + 0.5) / l as f64 * perimeter;
            let &(s, _) = layer
                .iter()
                .min_by(|a, b| (a.0 - want).abs().total_cmp(&(b.0 - want).abs()))
                .unwrap();
            s / perimeter
        })
        .collect();
    let contacts = place_contacts(&shape, &grid, &positions, 1e-9, &vec![1e-3; l], RS);
    assert!(
        contacts.iter().all(|c| c.nodes.len() == 1),
        "one node per point electrode"
    );
    let net = Network::new(grid, contacts, 1.0 / RS).unwrap();
    let t = net.solve(&net.conductances(None)).unwrap().transfer;
    let at = |e: usize| net.grid.nodes[net.contacts[e].nodes[0].0 as usize];
    let phi = |x: [f64; 2], a: usize, b: usize| {
        1e-5 * (disc_green(x, at(a), r) - disc_green(x, at(b), r))
    };
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in [(0, 8), (0, 4), (3, 10)] {
        for p in 0..l {
            let q = (p + 1) % l;
            if [a, b].contains(&p) || [a, b].contains(&q) {
                continue;
            }
            let want = phi(at(p), a, b) - phi(at(q), a, b);
            let got = t.voltage(a, b, p, q, 1e-5);
            num += (got - want).powi(2);
            den += want * want;
        }
    }
    (num / den).sqrt()
}

#[test]
fn disc_agrees_with_the_analytic_point_electrode_solution() {
    // Measured (cargo test -p et-sim disc -- --nocapture): 0.18 % at 8 mm, 0.07 % at 4 mm,
    // 0.18 % at 2 mm: what is left is lattice noise around the point sources.
    for (h, bound) in [(0.008, 0.005), (0.004, 0.005), (0.002, 0.005)] {
        let err = disc_error(h);
        println!(
            "disc vs analytic, h = {} mm: relative RMS error {:.4}",
            h * 1e3,
            err
        );
        assert!(err < bound, "h = {h}: {err} >= {bound}");
    }
}

#[test]
fn bad_networks_are_refused() {
    let shape = Shape::Rectangle {
        width: 0.01,
        height: 0.01,
    };
    let grid = Grid::new(&shape, 0.002);
    // 32 electrodes 3 mm wide on a 1 cm square at 2 mm spacing must overlap.
    let contacts = place_contacts(&shape, &grid, &equally_spaced(32), 0.003, &[10.0; 32], RS);
    assert!(matches!(
        Network::new(grid.clone(), contacts, 1.0 / RS),
        Err(NetworkError::Overlap { .. })
    ));
    let one = place_contacts(&shape, &grid, &[0.1], 0.001, &[10.0], RS);
    assert!(matches!(
        Network::new(grid.clone(), one, 1.0 / RS),
        Err(NetworkError::TooFewElectrodes)
    ));
    let two = place_contacts(&shape, &grid, &[0.05, 0.55], 0.001, &[10.0, 10.0], RS);
    let net = Network::new(grid, two, 1.0 / RS).unwrap();
    let mut g = net.conductances(None);
    g[3] = f64::NAN;
    assert!(matches!(
        net.solve(&g),
        Err(NetworkError::Conductance { .. })
    ));
    // A sheet cut in two by zero conductances, one electrode on each side, is refused, not
    // solved into an absurd Z. Electrode 0 sits at x < 0 (bottom side), electrode 1 at x > 0 (top).
    let xs = |e: usize| {
        net.contacts[e]
            .nodes
            .iter()
            .map(|&(n, _)| net.grid.nodes[n as usize][0])
            .collect::<Vec<_>>()
    };
    assert!(
        xs(0).iter().all(|&x| x < 0.0) && xs(1).iter().all(|&x| x > 0.0),
        "{:?} {:?}",
        xs(0),
        xs(1)
    );
    let cut: Vec<f64> = net
        .grid
        .edges
        .iter()
        .map(|e| {
            let (a, b) = (net.grid.nodes[e.u as usize], net.grid.nodes[e.v as usize]);
            if (a[0] < 0.0) != (b[0] < 0.0) {
                0.0
            } else {
                1.0 / RS
            }
        })
        .collect();
    let err = net.solve(&cut).unwrap_err();
    assert!(err.to_string().contains("no path"), "{err}");
}
