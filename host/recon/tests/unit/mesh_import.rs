use et_core::protocol::{Protocol, ProtocolKind};
use et_core::sheet::Sheet;
use et_recon::fem::{Electrodes, Forward};
use et_recon::mesh::MeshSize;
use et_recon::mesh::*;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("et-mesh-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `mesh` as Gmsh 2.2 (1-based ids, electrodes as physical lines 101, 102, ...,
/// triangles written clockwise for the reader to turn).
fn to_gmsh(mesh: &Mesh) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
    let _ = writeln!(s, "{}", mesh.nodes.len());
    for (i, p) in mesh.nodes.iter().enumerate() {
        let _ = writeln!(s, "{} {} {} 0", i + 1, p[0], p[1]);
    }
    let lines: Vec<(usize, [usize; 2])> = mesh
        .electrodes
        .iter()
        .enumerate()
        .flat_map(|(l, e)| e.iter().map(move |&x| (l, x)))
        .collect();
    let _ = writeln!(
        s,
        "$EndNodes\n$Elements\n{}",
        lines.len() + mesh.triangles.len()
    );
    let mut id = 1;
    for (l, [a, b]) in &lines {
        let _ = writeln!(s, "{id} 1 2 {} 1 {} {}", 101 + l, a + 1, b + 1);
        id += 1;
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "{id} 2 2 1 1 {} {} {}", t[0] + 1, t[2] + 1, t[1] + 1);
        id += 1;
    }
    s.push_str("$EndElements\n");
    s
}

/// An electrode's nodes in order along it.
fn chain(edges: &[[usize; 2]]) -> Vec<usize> {
    let mut c = vec![edges[0][0], edges[0][1]];
    let mut left: Vec<[usize; 2]> = edges[1..].to_vec();
    while let Some(i) = left
        .iter()
        .position(|e| e.contains(c.last().unwrap()) || e.contains(&c[0]))
    {
        let e = left.remove(i);
        let last = *c.last().unwrap();
        match () {
            () if e[0] == last => c.push(e[1]),
            () if e[1] == last => c.push(e[0]),
            () if e[0] == c[0] => c.insert(0, e[1]),
            () => c.insert(0, e[0]),
        }
    }
    c
}

#[test]
fn gmsh_and_csv_meshes_give_the_same_voltages_as_the_original() {
    let spec = Sheet::rectangle(0.13, 0.13, 8);
    let mesh = Mesh::of_sheet(&spec, MeshSize::for_count(&spec, 800)).unwrap();
    let dir = tmp("rt");
    let msh = dir.join("m.msh");
    std::fs::write(&msh, to_gmsh(&mesh)).unwrap();
    let g = Mesh::from_gmsh(&msh).unwrap();
    let write = |name: &str, rows: Vec<String>| {
        let p = dir.join(name);
        std::fs::write(&p, rows.join("\n")).unwrap();
        p
    };
    let nodes = write(
        "nodes.csv",
        std::iter::once("x,y".to_string())
            .chain(mesh.nodes.iter().map(|p| format!("{},{}", p[0], p[1])))
            .collect(),
    );
    let tris = write(
        "triangles.csv",
        mesh.triangles
            .iter()
            .map(|t| format!("{},{},{}", t[0], t[1], t[2]))
            .collect(),
    );
    let els = write(
        "electrodes.csv",
        mesh.electrodes
            .iter()
            .map(|e| {
                chain(e)
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect(),
    );
    let c = Mesh::from_csv(&nodes, &tris, &els).unwrap();
    let protocol = Protocol::new(ProtocolKind::Adjacent, 8).unwrap();
    let frame = |m: Mesh| {
        let n = m.triangles.len();
        Forward::new(m, Electrodes::Complete(vec![5.0; 8]))
            .unwrap()
            .frame(&vec![1e-4; n], &protocol.schedule(1e-4).unwrap())
            .unwrap()
    };
    let (v, vg, vc) = (frame(mesh), frame(g), frame(c));
    for k in 0..v.len() {
        let tol = 1e-9 * v[k].abs().max(1e-3);
        assert!(
            (v[k] - vg[k]).abs() < tol,
            "gmsh row {k}: {} vs {}",
            v[k],
            vg[k]
        );
        assert!(
            (v[k] - vc[k]).abs() < tol,
            "csv row {k}: {} vs {}",
            v[k],
            vc[k]
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// One-node electrodes (a CSV row of one index, a Gmsh physical point) are point
/// electrodes: the same voltages as the point model on the original mesh; the complete
/// model refuses them by name; a node inside the mesh, or a node mixed with edges, is
/// refused.
#[test]
fn one_node_electrodes_are_point_electrodes() {
    let spec = Sheet::rectangle(0.13, 0.13, 8);
    let mesh = Mesh::of_sheet(&spec, MeshSize::for_count(&spec, 800)).unwrap();
    let dir = tmp("point");
    let write = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let rows = |v: &mut dyn Iterator<Item = String>| v.collect::<Vec<_>>().join("\n");
    let nodes = write(
        "nodes.csv",
        rows(&mut mesh.nodes.iter().map(|p| format!("{},{}", p[0], p[1]))),
    );
    let tris = write(
        "triangles.csv",
        rows(
            &mut mesh
                .triangles
                .iter()
                .map(|t| format!("{},{},{}", t[0], t[1], t[2])),
        ),
    );
    let els = write(
        "electrodes.csv",
        rows(&mut mesh.centre_nodes.iter().map(usize::to_string)),
    );
    let c = Mesh::from_csv(&nodes, &tris, &els).unwrap();
    assert!(c.electrodes.iter().all(Vec::is_empty));
    assert_eq!(c.centre_nodes, mesh.centre_nodes);
    // Gmsh: the same electrodes as physical points.
    let mut g = to_gmsh(&Mesh {
        electrodes: vec![Vec::new(); 8],
        ..mesh.clone()
    });
    let points: String = mesh
        .centre_nodes
        .iter()
        .enumerate()
        .map(|(l, &i)| format!("{} 15 2 {} 1 {}\n", 900_000 + l, 201 + l, i + 1))
        .collect();
    let count = mesh.triangles.len();
    g = g.replacen(
        &format!("$Elements\n{count}\n"),
        &format!("$Elements\n{}\n{points}", count + 8),
        1,
    );
    let g = Mesh::from_gmsh(&write("p.msh", g)).unwrap();
    assert_eq!(g.centre_nodes, mesh.centre_nodes);
    let protocol = Protocol::new(ProtocolKind::Adjacent, 8).unwrap();
    let frame = |m: Mesh| {
        let n = m.triangles.len();
        Forward::new(m, Electrodes::Point)
            .unwrap()
            .frame(&vec![1e-4; n], &protocol.schedule(1e-4).unwrap())
            .unwrap()
    };
    let v = frame(mesh.clone());
    for other in [frame(c.clone()), frame(g)] {
        for (a, b) in v.iter().zip(&other) {
            assert!((a - b).abs() < 1e-9 * a.abs().max(1e-3), "{a} vs {b}");
        }
    }
    let e = Forward::new(c, Electrodes::Complete(vec![5.0; 8])).unwrap_err();
    assert!(e.to_string().contains("point"), "{e}");
    // A node inside the mesh (not on the boundary), and a node mixed with edges.
    let inner = (0..mesh.nodes.len())
        .find(|&i| spec.shape.distance_to_outline(mesh.nodes[i]) > 0.01)
        .unwrap();
    let mut bad: Vec<String> = mesh.centre_nodes.iter().map(usize::to_string).collect();
    bad[3] = inner.to_string();
    let e = Mesh::from_csv(&nodes, &tris, &write("bad.csv", bad.join("\n"))).unwrap_err();
    assert!(
        e.to_string()
            .contains(&format!("electrode 3: node {inner} is inside")),
        "{e}"
    );
    let mut electrodes: Vec<Vec<[usize; 2]>> =
        mesh.centre_nodes.iter().map(|&i| vec![[i, i]]).collect();
    electrodes[2].push(mesh.electrodes[2][0]);
    let e = Mesh::from_parts(mesh.nodes.clone(), mesh.triangles.clone(), electrodes).unwrap_err();
    assert!(e.to_string().contains("electrode 2 mixes"), "{e}");
    // Two electrodes on one node are shorted together: refused, naming both.
    let mut shared: Vec<String> = mesh.centre_nodes.iter().map(usize::to_string).collect();
    shared[5] = shared[4].clone();
    let e = Mesh::from_csv(&nodes, &tris, &write("shared.csv", shared.join("\n"))).unwrap_err();
    assert!(
        e.to_string().contains("electrodes 4 and 5 share node"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_files_name_the_file_and_line_and_slivers_stay_finite() {
    let dir = tmp("bad");
    let p = dir.join("v4.msh");
    std::fs::write(&p, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n").unwrap();
    let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
    assert!(e.contains("v4.msh:2") && e.contains("msh22"), "{e}");
    // One CSV alone, an et recording, and a file that is not text (pyEIT's arrays in an .npz):
    // said with what a mesh file is ("no $MeshFormat: not a Gmsh file" alone; the table reader's "save a sheet
    // as CSV").
    for (name, bytes, said) in [
        (
            "nodes.csv",
            &b"0,0\n1,0\n"[..],
            "nodes.csv:1: no $MeshFormat: not a Gmsh file; a mesh is",
        ),
        (
            "r.jsonl",
            b"{\"format\":\"et-recording\",\"version\":1}\n",
            "r.jsonl: an et recording (et sim, et record), not a mesh; a mesh is",
        ),
        (
            "mesh.npz",
            b"PK\x03\x04\x14\x00\xb8\xff",
            "mesh.npz: a zip archive",
        ),
    ] {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
        assert!(
            e.contains(said)
                && e.contains("nodes.csv,triangles.csv,electrodes.csv")
                && !e.contains("save a sheet"),
            "{e}"
        );
    }
    let p = dir.join("n.msh");
    std::fs::write(
        &p,
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 x 1 0\n$EndNodes\n",
    )
    .unwrap();
    let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
    assert!(e.contains("n.msh:7"), "{e}");
    // Counts beyond what the file holds are refused before anything is allocated (10^18
    // nodes was a capacity-overflow panic, 10^10 an allocation abort).
    for (section, count) in [("Nodes", "1000000000000000000"), ("Nodes", "10000000000")] {
        let p = dir.join("huge.msh");
        std::fs::write(
            &p,
            format!("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n${section}\n{count}\n1 0 0 0\n"),
        )
        .unwrap();
        let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
        assert!(e.contains("huge.msh:5") && e.contains(count), "{e}");
    }
    let p = dir.join("huge-el.msh");
    std::fs::write(
        &p,
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n99999999999\n1 2 3 1 1 1 1\n",
    )
    .unwrap();
    let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
    assert!(e.contains("99999999999 elements"), "{e}");
    // An element whose tag count runs past its line, or with the wrong number of nodes for
    // its type, is refused by line (it used to be dropped silently).
    for (line, what) in [
        ("1 2 99999999999 1 1 1 2 3", "99999999999 tags"),
        ("1 2 -1 1 2 3", "tags"),
        ("1 2 2 1 1 1 2 3 4", "has 3 nodes, this line gives 4"),
        ("1 1 2 1 1 1", "has 2 nodes, this line gives 1"),
        // Elements of other types were dropped: a quadrangle left a hole, second-order
        // triangles "no triangles".
        (
            "1 3 2 1 1 1 2 4 3",
            "type 3, a quadrangle: mesh with triangles",
        ),
        ("1 9 2 1 1 1 2 3 1 2 3", "a second- or higher-order element"),
        ("1 4 2 1 1 1 2 3 4", "a 3-D element: mesh the sheet in 2-D"),
    ] {
        let p = dir.join("el.msh");
        std::fs::write(
            &p,
            format!(
                "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n\
                 4 1 1 0\n$EndNodes\n$Elements\n1\n{line}\n$EndElements\n"
            ),
        )
        .unwrap();
        let e = Mesh::from_gmsh(&p).unwrap_err().to_string();
        assert!(e.contains("el.msh:13") && e.contains(what), "{line}: {e}");
    }
    let p = dir.join("t.csv");
    std::fs::write(&p, "a,b,c\n0,1,2\n0,1\n").unwrap();
    let e = Mesh::from_csv(&p, &p, &p).unwrap_err().to_string();
    assert!(e.contains("t.csv:2"), "{e}");
    // A row of the wrong width says what it holds and what each row is (a frame given as the
    // nodes was "expected 2 numbers"); a cell that is no number is named.
    assert!(
        e.contains("3 cells, where each row is a node's x, y (m)"),
        "{e}"
    );
    let (tri3, els) = (dir.join("tri3.csv"), dir.join("e.csv"));
    std::fs::write(&p, "0,0\n1,0\n0,1\n").unwrap();
    std::fs::write(&tri3, "0,1,2\n").unwrap();
    std::fs::write(&els, "0,1\n1,x\n").unwrap();
    let e = Mesh::from_csv(&p, &tri3, &els).unwrap_err().to_string();
    assert!(e.contains("e.csv:2: 'x' is not a number"), "{e}");
    // Line numbers are the file's, past comments, blank lines and the header; a node number
    // past the nodes is named by the file and line that gives it.
    let (nodes, tris, els) = (dir.join("n.csv"), dir.join("tri.csv"), dir.join("el.csv"));
    std::fs::write(&tris, "0,1,2\n\n0,1,9\n").unwrap();
    std::fs::write(&els, "0,1\n1,2\n").unwrap();
    std::fs::write(&nodes, "# made by hand\n\nx,y\n0,0\n1,0\nnan,1\n").unwrap();
    let e = Mesh::from_csv(&nodes, &tris, &els).unwrap_err().to_string();
    assert!(e.contains("n.csv:6") && e.contains("non-finite"), "{e}");
    std::fs::write(&nodes, "# made by hand\n\nx,y\n0,0\n1,0\n0,1\n").unwrap();
    let e = Mesh::from_csv(&nodes, &tris, &els).unwrap_err().to_string();
    assert!(e.contains("tri.csv:3") && e.contains("node 9"), "{e}");
    // A sliver of zero area is refused; one of tiny area keeps finite potentials.
    let nodes = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.0]];
    let tris = vec![[0, 4, 1], [0, 1, 2], [0, 2, 3]];
    let flat = Mesh::from_parts(
        nodes.clone(),
        tris.clone(),
        vec![vec![[0, 4]], vec![[2, 3]]],
    );
    assert!(matches!(
        flat,
        Err(MeshError::Degenerate { triangle: 0, .. })
    ));
    let mut thin = nodes;
    thin[4] = [0.5, -1e-7];
    let m = Mesh::from_parts(thin, tris, vec![vec![[0, 4], [4, 1]], vec![[2, 3]]]).unwrap();
    let fwd = Forward::new(m, Electrodes::Complete(vec![1.0, 1.0])).unwrap();
    let c = nalgebra::DMatrix::from_column_slice(2, 1, &[1e-3, -1e-3]);
    let sol = fwd.solve(&[1.0, 1.0, 1.0], &c).unwrap();
    assert!(sol.nodes.iter().all(|v| v.is_finite()));
    let out_of_range = Mesh::from_parts(
        vec![[0.0, 0.0]; 3],
        vec![[0, 1, 5]],
        vec![vec![[0, 1]], vec![[1, 2]]],
    );
    assert!(matches!(
        out_of_range,
        Err(MeshError::TriangleNodePast {
            triangle: 0,
            nodes: 3
        })
    ));
    // Topology: each fault named (they were accepted and changed the voltages).
    let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let two = vec![[0, 1, 2], [0, 2, 3]];
    let good = vec![vec![[0, 1]], vec![[2, 3]]];
    Mesh::from_parts(square.clone(), two.clone(), good.clone()).unwrap();
    type Parts = (Vec<[f64; 2]>, Vec<[usize; 3]>, Vec<Vec<[usize; 2]>>);
    // A sheet with a hole (a square ring) is a mesh.
    let ring = vec![
        [0.0, 0.0],
        [3.0, 0.0],
        [3.0, 3.0],
        [0.0, 3.0],
        [1.0, 1.0],
        [2.0, 1.0],
        [2.0, 2.0],
        [1.0, 2.0],
    ];
    let ring_triangles = vec![
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ];
    Mesh::from_parts(ring, ring_triangles, good.clone()).unwrap();
    let cases: [(Parts, &str); 6] = [
        // A triangle laid over the two (it shares their edges at node 0), and a piece no
        // electrode reaches: the first added conductance, the second failed as "conductivities
        // that span too many powers of ten".
        (
            (
                square.clone(),
                vec![[0, 1, 2], [0, 2, 3], [0, 1, 3]],
                good.clone(),
            ),
            "triangles 0 and 2 overlap at node 0",
        ),
        (
            (
                [square.clone(), vec![[3.0, 3.0], [4.0, 3.0], [3.0, 4.0]]].concat(),
                vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]],
                good.clone(),
            ),
            "triangle 2 is in a piece of the mesh that no electrode reaches (1 of its triangles)",
        ),
        (
            (
                square.clone(),
                vec![[0, 1, 2], [0, 2, 3], [2, 0, 1]],
                good.clone(),
            ),
            "triangle 2 repeats triangle 0",
        ),
        (
            (
                [square.clone(), vec![[2.0, 2.0]]].concat(),
                two.clone(),
                good.clone(),
            ),
            "node 4 is in no triangle",
        ),
        (
            (
                square.clone(),
                two.clone(),
                vec![vec![[0, 2]], vec![[2, 3]]],
            ),
            "edge (0, 2) is inside the mesh",
        ),
        (
            (square, two, vec![vec![[1, 3]], vec![[2, 3]]]),
            "nodes 1 and 3 share no triangle edge",
        ),
    ];
    for ((nodes, tris, electrodes), what) in cases {
        let e = Mesh::from_parts(nodes, tris, electrodes)
            .unwrap_err()
            .to_string();
        assert!(e.contains(what), "{what}: {e}");
    }
    // Two squares laid over each other with no node in common (a sheet meshed folded, or
    // pieces stacked), each reached by an electrode: no corner overlaps another at a shared
    // node, so only their boundaries crossing shows it (the finite elements added their
    // conductances where they overlap, without a word).
    let stacked = vec![
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, 1.0],
        [0.0, 1.0],
        [0.5, 0.5],
        [1.5, 0.5],
        [1.5, 1.5],
        [0.5, 1.5],
    ];
    let e = Mesh::from_parts(
        stacked,
        vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
        vec![vec![[0, 1]], vec![[5, 6]]],
    )
    .unwrap_err();
    assert!(matches!(e, MeshError::BoundaryCrossing { .. }), "{e}");
    assert!(
        e.to_string().contains("the mesh's boundary crosses itself"),
        "{e}"
    );
    // A slit cut in from the edge (its nodes doubled along the cut, each side a boundary)
    // is a sheet: its sides along one line and its doubled nodes at one point cross nothing.
    let slit = vec![
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 2.0],
        [0.0, 2.0],
        [0.0, 1.0],
        [0.0, 1.0],
        [1.0, 1.0],
    ];
    Mesh::from_parts(
        slit,
        vec![[0, 1, 6], [0, 6, 4], [1, 2, 6], [2, 3, 6], [3, 5, 6]],
        vec![vec![[0, 1]], vec![[2, 3]]],
    )
    .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}
