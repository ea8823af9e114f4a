//! The garment tests of issue #22 on coarse meshes (1 500 vertices, a few seconds each,
//! with cloth–cloth contact, the default):
//! openings, contact with the body, self-intersection, triangle quality, rest, metric UVs
//! and grain. One mannequin (size M) is built once and shared.

use super::check;
use super::{Body, BodyParams, Garment, GarmentKind, GarmentOptions, Size, make};
use std::sync::OnceLock;

fn body() -> &'static Body {
    static BODY: OnceLock<Body> = OnceLock::new();
    BODY.get_or_init(|| Body::new(&BodyParams::new(Size::M)).unwrap())
}

fn garment(kind: GarmentKind) -> Garment {
    let mut o = GarmentOptions::new(Size::M);
    o.vertices = 1500;
    let (g, _) = make(kind, &o, Some(body().clone()), &mut |_, _| {}).unwrap();
    g
}

/// Bounds a garment must meet.
struct Bounds {
    openings: usize,
    /// Largest |A_3D / A_panel − 1| of any triangle.
    area_distortion: f64,
    /// The same for 99 % of the triangles.
    area_distortion_p99: f64,
    /// Largest turn of the warp across an edge inside a panel (degrees).
    warp_jump_deg: f64,
    /// Largest disagreement of the tangent frames across a seam (degrees).
    seam_frame_deg: f64,
}

/// The bounds of both tops (T-shirt and shirt).
const TOPS: Bounds = Bounds {
    openings: 4,
    area_distortion: 0.75,
    area_distortion_p99: 0.3,
    warp_jump_deg: 35.0,
    seam_frame_deg: 35.0,
};

fn check_garment(kind: GarmentKind, b: Bounds) -> Garment {
    let g = garment(kind);
    let m = &g.mesh;
    let topo = check::topology(m.positions.len(), &m.triangles);
    let d = check::area_distortion(m);
    let worst = d.iter().fold(0.0f64, |w, x| w.max(x.abs()));
    let mut sorted: Vec<f64> = d.iter().map(|x| x.abs()).collect();
    sorted.sort_by(f64::total_cmp);
    let p99 = sorted[sorted.len() * 99 / 100];
    eprintln!(
        "{}: area distortion p50 {:.4} p99 {p99:.4} max {worst:.4}",
        kind.name(),
        sorted[sorted.len() / 2]
    );
    let grain = check::grain(m, &g.triangle_panel);
    let (angle, area) = check::worst_triangle(m);
    let vd = check::min_vertex_distance(m, &body().sdf);
    let td = check::min_body_distance(m, &body().sdf);
    let si = check::self_intersections(m).len();
    eprintln!(
        "{}: {} v, {topo:?}, distortion {worst:.3}, {grain:?}, angle {angle:.1}°, area {area:.2e}, vertex d {vd:.5}, tri d {td:.5}, {si} self-int, drape {:?}, gap {:.4}",
        kind.name(),
        m.positions.len(),
        g.drape,
        g.seam_gap_at_weld_m
    );
    // One manifold, orientable piece whose boundary loops are the openings.
    assert_eq!(topo.boundary_loops.len(), b.openings, "{topo:?}");
    assert_eq!(
        (
            topo.non_manifold_edges,
            topo.non_manifold_vertices,
            topo.misoriented_edges,
            topo.components
        ),
        (0, 0, 0, 1)
    );
    // Every vertex outside the body: the solver leaves each at ≥ T after its last
    // projection (T = 3 mm); between vertices a chord over the body's curvature may dip
    // in by h²/(8R) ≈ (0.05 m)²/(8·0.05 m) ≈ 6 mm at most, so sampled triangles stay > −T.
    let t = g.fabric.thickness_m;
    // The projection follows the gradient of the trilinear distance (first order) and
    // friction then moves the node tangentially: it lands within 20 % of T (measured: the
    // T-shirt's closest vertex 0.84 T since the seams are sewn without friction, 0.9 T
    // before).
    assert!(vd >= 0.8 * t, "vertex {vd} m from the body");
    assert!(td > -t, "triangle point {td} m inside the body");
    // Free of crossings: the panels are placed apart, sewn and draped with cloth–cloth
    // contact, and the few a seam junction leaves are smoothed out.
    assert_eq!(si, 0, "self-intersecting triangle pairs");
    // No degenerate triangle: the mesher's angles survive the drape.
    assert!(
        angle > 5.0 && area > 1e-3 * g.spacing_m * g.spacing_m,
        "angle {angle}°, area {area} m²"
    );
    // At rest: kinetic energy below 1e-5 J/kg (RMS speed 4.5 mm/s) held for 0.1 s.
    assert!(
        g.drape.settled
            && g.drape.kinetic_energy_per_kg < super::DrapeSettings::default().rest_ke_per_kg,
        "{:?}",
        g.drape
    );
    // Metric UVs: every triangle keeps its panel area within the bound.
    assert!(worst < b.area_distortion, "area distortion {worst}");
    assert!(p99 < b.area_distortion_p99, "area distortion p99 {p99}");
    assert_eq!(grain.mirrored, 0);
    assert!(grain.warp_jump_max_deg < b.warp_jump_deg, "{grain:?}");
    assert!(grain.seam_frame_max_deg < b.seam_frame_deg, "{grain:?}");
    g
}

#[test]
fn garment_tshirt() {
    // The tops' grain bounds (35°): measured warp jump 15.1°, seam frames 16.1° (the shirt
    // 23.9° and 20.9°), turned at the armpit where four panels meet.
    check_garment(GarmentKind::TShirt, TOPS);
}

/// The long-sleeved shirt: its underarm seams used to stall 19.6 mm open (the sleeves held
/// on the arm by the body's friction); sewn without friction they close.
#[test]
fn garment_shirt() {
    let g = check_garment(GarmentKind::Shirt, TOPS);
    assert!(g.seam_gap_at_weld_m < 0.005, "seams {} m open", g.seam_gap_at_weld_m);
}

#[test]
fn garment_trousers() {
    check_garment(
        GarmentKind::Trousers,
        Bounds {
            openings: 3,
            area_distortion: 0.75,
            area_distortion_p99: 0.3,
            warp_jump_deg: 35.0,
            seam_frame_deg: 35.0,
        },
    );
}

#[test]
fn garment_skirt() {
    check_garment(
        GarmentKind::Skirt,
        Bounds {
            openings: 2,
            area_distortion: 0.5,
            area_distortion_p99: 0.3,
            warp_jump_deg: 20.0,
            seam_frame_deg: 10.0,
        },
    );
}

/// A garment at its default vertex count (10 000; the scarf 3 000), where the mesh is fine
/// enough that layers press on each other.
fn garment_10k(kind: GarmentKind) -> Garment {
    let mut o = GarmentOptions::new(Size::M);
    o.vertices = super::sew::default_vertices(kind);
    let (g, _) = make(kind, &o, Some(body().clone()), &mut |_, _| {}).unwrap();
    let si = check::self_intersections(&g.mesh).len();
    eprintln!(
        "{}: drape {:?}, seams {:.4} m, {si} crossings, {} smoothing rounds, last {:.4} m",
        kind.name(),
        g.drape,
        g.seam_gap_at_weld_m,
        g.untangle_rounds,
        g.final_smoothing_m
    );
    assert_eq!(si, 0, "self-intersecting triangle pairs");
    // No crumple left for the smoothing after the drape: the drape's own result.
    assert_eq!(g.final_smoothing_m, 0.0);
    assert!(g.drape.settled, "{:?}", g.drape);
    g
}

/// The T-shirt's armpit, a layer pressed between the body and the sleeve: with one pass of
/// cloth contact and body per sub-step it jittered until 2.1 s simulated and crumpled
/// through itself; alternated three times it rests after 0.77 s (bound 1.5 s).
#[test]
fn tshirt_at_10000_vertices_rests_without_crossings() {
    let g = garment_10k(GarmentKind::TShirt);
    assert!(g.drape.settle_time_s < 1.5, "{:?}", g.drape);
}

/// The trousers' inseams, hanging together between the lower legs: pushed off each other's
/// extended triangle planes (the contact's plane distance for nodes beside a triangle) they
/// never came to rest in 4 s and welded 4.3 mm apart; with true distances beside a triangle
/// they rest after 1.79 s (bound 2.5 s) with the seams 0.4 mm apart (bound 2 mm).
#[test]
fn trousers_at_10000_vertices_rest_without_crossings() {
    let g = garment_10k(GarmentKind::Trousers);
    assert!(g.drape.settle_time_s < 2.5, "{:?}", g.drape);
    assert!(g.seam_gap_at_weld_m < 0.002, "seams {} m open", g.seam_gap_at_weld_m);
}

/// The scarf, standing round the neck and hanging down the chest: one opening, free of
/// crossings (its old flat ring crumpled: 3 002 pairs at 10 000 vertices), at rest, every
/// vertex outside the body.
#[test]
fn scarf_at_its_3000_vertices_rests_without_crossings() {
    let g = garment_10k(GarmentKind::Scarf);
    let topo = check::topology(g.mesh.positions.len(), &g.mesh.triangles);
    assert_eq!((topo.boundary_loops.len(), topo.components), (1, 1), "{topo:?}");
    let vd = check::min_vertex_distance(&g.mesh, &body().sdf);
    assert!(vd >= 0.8 * g.fabric.thickness_m, "vertex {vd} m from the body");
}

/// Every size drafts both tops, each sleeve cap as long as its armhole (the seam sewn
/// between them). Size L's arm is too thick for its body's own armpit depth, so its
/// armhole is deepened; S and M keep theirs.
#[test]
fn every_size_drafts_tops_whose_sleeve_caps_fit_their_armholes() {
    use super::pattern::{Pattern, PatternOptions};
    for size in [Size::S, Size::M, Size::L] {
        let p = BodyParams::new(size);
        let man = super::body::Mannequin::new(&p).unwrap();
        for kind in [GarmentKind::TShirt, GarmentKind::Shirt] {
            let pat =
                Pattern::new(kind, &p.measurements, &man.landmarks, &PatternOptions::default())
                    .unwrap_or_else(|e| panic!("{size:?} {kind:?}: {e}"));
            let edge = |panel: usize, name: &str| {
                pat.panels[panel].edges.iter().find(|e| e.name == name).unwrap().length()
            };
            let (armhole, cap) = (edge(0, "armhole_r"), edge(2, "cap_r"));
            eprintln!("{size:?} {kind:?}: armhole {armhole:.4} m, sleeve cap half {cap:.4} m");
            assert!((armhole - cap).abs() < 1e-3 * armhole, "{size:?} {kind:?}");
        }
    }
}

/// The curtain (no body: its pleated heading pinned on a 0.9 m rod) comes to rest, keeps
/// its pleats down to the hem, and is one sheet with one opening and no crossing. At
/// 3 000 vertices (its pleats, 15 cm apart, need more than the 1 500 of the garments'
/// tests: at 1 500 a pleat kept moving after 4 s).
#[test]
fn curtain_rests_in_its_pleats() {
    let mut o = GarmentOptions::new(Size::M);
    o.vertices = 3000;
    let (g, _) = make(GarmentKind::Curtain, &o, Some(body().clone()), &mut |_, _| {}).unwrap();
    let m = &g.mesh;
    assert!(g.drape.settled, "curtain not at rest: {:?}", g.drape);
    assert!(g.drape.settle_time_s < 3.0, "rest after {} s", g.drape.settle_time_s);
    let topo = check::topology(m.positions.len(), &m.triangles);
    assert_eq!(topo.boundary_loops.len(), 1);
    assert!(check::self_intersections(m).is_empty());
    let d = check::area_distortion(m);
    let worst = d.iter().fold(0.0f64, |w, x| w.max(x.abs()));
    assert!(worst < 0.2, "area distortion {worst}");
    // The heading spans the rod; the hem is still gathered (narrower than the panel's
    // 1.2 m) and pleated (depth of the folds, y, at least half the heading's 2A).
    let rows = |z_lo: f64, z_hi: f64| {
        let pts: Vec<_> = m.positions.iter().filter(|p| p[2] >= z_lo && p[2] <= z_hi).collect();
        let span = |k: usize| {
            let lo = pts.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
            let hi = pts.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
            hi - lo
        };
        (span(0), span(1))
    };
    let top = m.positions.iter().map(|p| p[2]).fold(f64::NEG_INFINITY, f64::max);
    let bottom = m.positions.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    let (head_x, head_y) = rows(top - 1e-6, top);
    let (hem_x, hem_y) = rows(bottom, bottom + 0.02);
    eprintln!("heading {head_x:.3} × {head_y:.3} m, hem {hem_x:.3} × {hem_y:.3} m");
    assert!((head_x - 0.9).abs() < 0.01, "heading spans {head_x} m");
    assert!(hem_x < 1.1 && hem_y > 0.5 * head_y, "hem {hem_x} × {hem_y} m");
}

/// The pleats' wave is laid out by arc length: 1.2 m of panel gathered onto 0.9 m in six
/// pleats ends at the rod's end, and 1 mm steps of panel are 1 mm of wave (the chord of a
/// 1 mm arc of a wave whose curvature radius is ≥ 1 / (A k²) ≈ 16 mm is short of the arc
/// by < 2·10⁻⁷ m).
#[test]
fn pleats_gather_the_panel_isometrically() {
    let p = super::pattern::Pleats::new(1.2, 0.9, 6);
    let end = p.at(1.2);
    assert!((end[0] - 0.9).abs() < 1e-9 && end[1].abs() < 1e-6, "ends at {end:?}");
    assert!(p.amplitude > 0.02 && p.amplitude < 0.06, "amplitude {}", p.amplitude);
    let mut total = 0.0;
    for i in 0..1200 {
        let (a, b) = (p.at(i as f64 * 1e-3), p.at((i + 1) as f64 * 1e-3));
        let chord = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        assert!((chord - 1e-3).abs() < 2e-6, "step {i}: chord {chord}");
        total += chord;
    }
    assert!((total - 1.2).abs() < 1e-4, "total {total}");
}

/// The skirt's panels are placed with their side seams' partners side by side all the way
/// up (each arc of the cone's development spans the same angles round the body): within
/// 2 cm. Wrapped by panel `x` alone they were 19 cm apart at the waist, whose arc lay on a
/// fraction of its ellipse compressed by 39 %, and at 40 000 vertices the sewing's release
/// of that threw the skirt down to the ankles.
#[test]
fn skirt_panels_are_placed_with_their_seams_together() {
    let o = GarmentOptions::new(Size::M);
    let man = super::body::Mannequin::new(&o.body).unwrap();
    let p =
        super::Pattern::new(GarmentKind::Skirt, &o.body.measurements, &man.landmarks, &o.pattern)
            .unwrap();
    let n = 24;
    for s in &p.seams {
        let side = |e: super::pattern::EdgeRef| {
            let panel = &p.panels[e.panel];
            let pts = panel.edges[e.edge].resample(n);
            pts.iter().map(|&q| panel.placement.place(q)).collect::<Vec<_>>()
        };
        let (a, b) = (side(s.a), side(s.b));
        for k in 0..a.len() {
            let d = crate::vec3::length(crate::vec3::sub(a[k], b[b.len() - 1 - k]));
            assert!(d < 0.02, "seam point {k}: partners {d} m apart");
        }
    }
}

/// A sewing and drape stopped part-way and resumed from its snapshot ends bit for bit where
/// the uninterrupted run ends — resumed while sewing and while draping (the T-shirt at
/// 1 500 vertices, with cloth contact: the snapshot carries the contact list's sides).
#[test]
fn a_resumed_garment_is_bit_identical_to_an_uninterrupted_one() {
    use super::checkpoint::{Checkpointing, Snapshot};
    let mut o = GarmentOptions::new(Size::M);
    o.vertices = 1500;
    let key = super::checkpoint::fingerprint(format!("{o:?}").as_bytes());
    let mut saved: Vec<Vec<u8>> = Vec::new();
    let mut keep = |s: &Snapshot| {
        saved.push(s.to_bytes());
        Ok(())
    };
    let run = |ck: &mut Checkpointing<'_>| {
        super::make_resumable(
            GarmentKind::TShirt,
            &o,
            Some(body().clone()),
            &mut |_, _| {},
            Some(ck),
        )
        .unwrap()
        .0
    };
    let mut ck = Checkpointing::new(key, None, std::time::Duration::ZERO, &mut keep).unwrap();
    let whole = run(&mut ck);
    let snapshots: Vec<Snapshot> = saved.iter().map(|b| Snapshot::from_bytes(b).unwrap()).collect();
    let sewing: Vec<&Snapshot> = snapshots.iter().filter(|s| s.phase == 0).collect();
    let draping: Vec<&Snapshot> = snapshots.iter().filter(|s| s.phase >= 1).collect();
    assert!(sewing.len() >= 2 && draping.len() >= 2, "{} / {}", sewing.len(), draping.len());
    for from in [sewing[sewing.len() / 2], draping[draping.len() / 2]] {
        // The resumed run's first snapshot is 64 sub-steps after the one it resumed: it
        // went on from there rather than starting over (which would end the same).
        let mut first: Option<(u32, u64)> = None;
        let mut note = |s: &Snapshot| {
            first.get_or_insert((s.phase, s.steps));
            Ok(())
        };
        let mut ck =
            Checkpointing::new(key, Some(from.clone()), std::time::Duration::ZERO, &mut note)
                .unwrap();
        let resumed = run(&mut ck);
        assert_eq!(resumed.mesh.positions, whole.mesh.positions, "resumed at phase {}", from.phase);
        assert_eq!(resumed.drape, whole.drape);
        assert_eq!(resumed.sewing, whole.sewing);
        assert_eq!(resumed.untangle_rounds, whole.untangle_rounds);
        drop(ck);
        assert_eq!(first, Some((from.phase, from.steps + 64)));
    }
    // Another key (other parameters) is refused.
    let mut ignore = |_: &Snapshot| Ok(());
    let other =
        Checkpointing::new(key ^ 1, Some(draping[0].clone()), Default::default(), &mut ignore);
    assert!(other.is_err());
}
