//! OBJ validity of the synthetic meshes: loadable by tobj with UVs and normals, no
//! degenerate triangles, boundaries as intended, UV charts unmirrored, front sides
//! outwards, and a drape that rests on (not in) the sphere.

use datasets::mesh::cloth::{DrapeParams, drape, drape_frames};
use datasets::{Mesh, MeshKind, Resolution, synth_mesh, write_obj};

fn check_obj(mesh: &Mesh, name: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{name}.obj"));
    write_obj(mesh, &path, name).unwrap();
    let (models, _) =
        tobj::load_obj(&path, &tobj::LoadOptions { triangulate: true, ..Default::default() })
            .unwrap();
    // One model per material run (tobj splits at `usemtl`), one for a mesh without.
    assert_eq!(models.len(), mesh.material_names.len().max(1), "{name}");
    let faces: usize = models.iter().map(|m| m.mesh.indices.len()).sum();
    assert_eq!(faces, 3 * mesh.triangles.len(), "{name}");
    if let [one] = &models[..] {
        assert_eq!(one.mesh.positions.len(), 3 * mesh.positions.len(), "{name}");
    }
    for m in models.iter().map(|m| &m.mesh) {
        assert_eq!(m.texcoord_indices.len(), m.indices.len(), "{name}: UVs on every corner");
        assert_eq!(m.normal_indices.len(), m.indices.len(), "{name}: normals on every corner");
        assert!(m.texcoords.iter().all(|t| t.is_finite()));
    }
}

#[test]
fn garment_material_names_survive_an_obj_round_trip() {
    // usemtl/mtllib: tobj (what trimesh and most tools read the same way) loads the .mtl
    // written beside the OBJ and gives each face run its material's name back.
    for (kind, names) in [
        (MeshKind::Shirt, ["torso", "sleeve_right", "sleeve_left"]),
        (MeshKind::Trousers, ["hip", "leg_right", "leg_left"]),
    ] {
        let mesh = synth_mesh(kind, Resolution::Low).unwrap();
        assert_eq!(mesh.material_names, names);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.obj");
        write_obj(&mesh, &path, "g").unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("mtllib g.mtl\n")
                && text.contains("usemtl torso\n") == (names[0] == "torso")
        );
        let (models, mats) =
            tobj::load_obj(&path, &tobj::LoadOptions { triangulate: true, ..Default::default() })
                .unwrap();
        let mats = mats.unwrap();
        let got: Vec<&str> = mats.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(got, names);
        for (k, name) in names.iter().enumerate() {
            let faces: usize = models
                .iter()
                .filter(|m| m.mesh.material_id.map(|i| mats[i].name.as_str()) == Some(name))
                .map(|m| m.mesh.indices.len() / 3)
                .sum();
            let want = mesh.triangle_material.iter().filter(|&&t| t == k as u32).count();
            assert_eq!(faces, want, "{name}");
        }
    }
}

fn outward_fraction(mesh: &Mesh, outward: impl Fn([f64; 3]) -> [f64; 3]) -> f64 {
    let ok = mesh.positions.iter().zip(&mesh.normals).filter(|(p, n)| {
        let o = outward(**p);
        n[0] * o[0] + n[1] * o[1] + n[2] * o[2] > 0.0
    });
    ok.count() as f64 / mesh.positions.len() as f64
}

#[test]
fn parametric_meshes_are_valid_obj_with_intended_boundaries() {
    for (kind, name, boundary_loops_edges) in [
        (MeshKind::Plane, "plane", Some(4 * 29)),
        (MeshKind::Sphere, "sphere", Some(0)),
        (MeshKind::Curtain, "curtain", Some(2 * (36 + 25))),
        (MeshKind::Shirt, "shirt", None),
        (MeshKind::Trousers, "trousers", None),
    ] {
        let mesh = synth_mesh(kind, Resolution::Low).unwrap();
        let (boundary, non_manifold) = mesh.edge_counts();
        assert_eq!(non_manifold, 0, "{name}");
        if let Some(b) = boundary_loops_edges {
            assert_eq!(boundary, b, "{name}");
        }
        assert!(mesh.min_triangle_area() > 1e-7, "{name}: {}", mesh.min_triangle_area());
        assert_eq!(mesh.mirrored_uv_triangles(), 0, "{name}");
        let nv = mesh.positions.len();
        assert!((800..=1000).contains(&nv), "{name}: {nv} vertices");
        check_obj(&mesh, name);
    }
    // Garments: each part is a tube open at both ends (shirt: torso + 2 sleeves; trousers:
    // hip + 2 legs), i.e. two boundary rings per part.
    let shirt = synth_mesh(MeshKind::Shirt, Resolution::Low).unwrap();
    assert_eq!(shirt.edge_counts().0, 2 * 32 + 4 * 12);
    let trousers = synth_mesh(MeshKind::Trousers, Resolution::Low).unwrap();
    assert_eq!(trousers.edge_counts().0, 2 * 32 + 4 * 24);
    // Front sides face outwards.
    let sphere = synth_mesh(MeshKind::Sphere, Resolution::Low).unwrap();
    assert_eq!(outward_fraction(&sphere, |p| p), 1.0);
    let plane = synth_mesh(MeshKind::Plane, Resolution::Low).unwrap();
    assert_eq!(outward_fraction(&plane, |_| [0.0, 0.0, 1.0]), 1.0);
    let curtain = synth_mesh(MeshKind::Curtain, Resolution::Low).unwrap();
    assert!(outward_fraction(&curtain, |_| [0.0, -1.0, 0.0]) == 1.0);
    let legs = outward_fraction(&trousers, |p| [p[0] - 0.1 * p[0].signum(), p[1], 0.0]);
    assert!(legs > 0.8, "{legs}");
}

#[test]
fn high_resolution_has_about_9000_vertices() {
    for kind in
        [MeshKind::Plane, MeshKind::Sphere, MeshKind::Curtain, MeshKind::Shirt, MeshKind::Trousers]
    {
        let n = synth_mesh(kind, Resolution::High).unwrap().positions.len();
        assert!((8500..=9500).contains(&n), "{kind:?}: {n}");
    }
}

#[test]
fn drape_rests_on_the_sphere_and_hangs_down() {
    let p = DrapeParams::new(20);
    let r = drape(&p).unwrap();
    let m = &r.mesh;
    assert!(r.max_penetration_m < 0.5 * p.thickness_m, "penetration {}", r.max_penetration_m);
    // The centre of the cloth sits on the sphere's top, within the force-field thickness.
    let centre = m.positions[10 * 20 + 10];
    let dist =
        (centre[0].powi(2) + centre[1].powi(2) + centre[2].powi(2)).sqrt() - p.sphere_radius_m;
    assert!((0.0..=p.thickness_m).contains(&dist), "centre {centre:?}: {dist}");
    // The corners have fallen well below the top, and no spring is stretched far beyond
    // its slack interval.
    let corner_z = m.positions[0][2];
    assert!(corner_z < 0.0, "corner at {corner_z}");
    let (boundary, non_manifold) = m.edge_counts();
    assert_eq!((boundary, non_manifold), (4 * 19, 0));
    // UVs are metres of flat cloth, so an edge's UV length is its rest length.
    let mut max_strain = 0f64;
    for (t, tu) in m.triangles.iter().zip(&m.triangle_uvs) {
        for k in 0..3 {
            let [a, b] = [m.positions[t[k] as usize], m.positions[t[(k + 1) % 3] as usize]];
            let [ua, ub] = [m.uvs[tu[k] as usize], m.uvs[tu[(k + 1) % 3] as usize]];
            let l = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            let rest = ((ua[0] - ub[0]).powi(2) + (ua[1] - ub[1]).powi(2)).sqrt();
            max_strain = max_strain.max((l / rest - 1.0).abs());
        }
    }
    // Within the 3 % slack plus the small elastic stretch under the cloth's weight; folds
    // may compress an edge slightly more.
    assert!(max_strain < 0.1, "max strain {max_strain}");
    assert!(m.min_triangle_area() > 1e-6);
    assert_eq!(m.mirrored_uv_triangles(), 0);
    check_obj(m, "drape");
    eprintln!("drape n=20: {} steps, {} halvings", r.steps, r.halvings);
}

#[test]
fn drape_frames_run_from_the_flat_cloth_to_the_drape() {
    let p = DrapeParams::new(12);
    let (r, frames) = drape_frames(&p, 4).unwrap();
    assert_eq!(frames.len(), 5);
    // Frame 0 is the flat start; the last frame is the settled drape; the result is the
    // same as without recording.
    let z0 = frames[0].positions[0][2];
    assert!(frames[0].positions.iter().all(|q| q[2] == z0));
    assert_eq!(frames[4].positions, r.mesh.positions);
    assert_eq!(drape(&p).unwrap().mesh.positions, r.mesh.positions);
    for f in &frames {
        assert_eq!(f.uvs, frames[0].uvs);
        assert_eq!(f.triangles, frames[0].triangles);
    }
    // A corner falls from the start, passes below the sphere's centre and (hanging, it
    // may swing back a little as the cloth settles) ends well below where it began.
    let corner: Vec<f64> = frames.iter().map(|f| f.positions[0][2]).collect();
    assert!(corner[1] < corner[0] && corner.iter().skip(2).all(|&z| z < 0.0), "{corner:?}");
    assert!(corner[4] < corner[0] - 0.4, "{corner:?}");
}
