use super::*;
use crate::patch::fibers_from_polylines;
use crate::rng::Rng;

fn random_fibers(n: usize, seed: u64) -> Fibers {
    let mut rng = Rng::new(&[seed]);
    let lines: Vec<Vec<V3>> = (0..n)
        .map(|_| {
            let p = rng.uniform3();
            let mut pts = vec![p];
            for _ in 0..4 {
                let q = *pts.last().unwrap();
                let s = rng.uniform3();
                pts.push([
                    q[0] + 0.05 * (s[0] - 0.5),
                    q[1] + 0.05 * (s[1] - 0.5),
                    q[2] + 0.05 * (s[2] - 0.5),
                ]);
            }
            pts
        })
        .collect();
    fibers_from_polylines(&lines, 0.004, [0.5; 3])
}

#[test]
fn bvh_closest_and_any_hit_agree_with_brute_force() {
    let fibers = random_fibers(400, 1);
    let scene = FiberScene::new(&fibers, &SceneOptions::default()).unwrap();
    let mut rng = Rng::new(&[2]);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = rng.uniform3().map(|x| 3.0 * x - 1.0);
        let target = rng.uniform3();
        let d = vec3::normalize(vec3::sub(target, o)).unwrap();
        let got = scene.intersect(o, d, f64::INFINITY, None);
        let want = scene
            .segments
            .iter()
            .enumerate()
            .filter_map(|(i, s)| {
                entry(
                    s.a.map(f64::from),
                    s.b.map(f64::from),
                    s.radius as f64,
                    o,
                    d,
                    0.0,
                    f64::INFINITY,
                )
                .map(|h| (i, h.t))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match (got, want) {
            (Some(g), Some(w)) => {
                hits += 1;
                assert!((g.t - w.1).abs() <= 1e-12 * w.1.max(1.0), "{} vs {}", g.t, w.1);
            }
            (None, None) => {}
            (g, w) => panic!("bvh {g:?} vs brute force {w:?}"),
        }
        assert_eq!(scene.occluded(o, d, f64::INFINITY, None), want.is_some());
        if let Some(w) = want {
            assert!(!scene.occluded(o, d, w.1 * (1.0 - 1e-9), None));
        }
    }
    assert!(hits > 200, "only {hits} hits: the test rays miss too often");
}

#[test]
fn periodic_wrap_sees_the_infinite_tiling() {
    // One fiber along y crossing the box's +x wall at x = 0.95 ± 0.1 (radius): a ray at
    // x = 0.02 (the next tile's copy of x = 1.02) must hit the copy, a ray far away in x
    // (tile 7) hits it too, and a ray through the gap misses.
    let fibers = fibers_from_polylines(&[vec![[0.95, 0.1, 0.0], [0.95, 0.9, 0.0]]], 0.1, [1.0; 3]);
    let per = Period { origin: [0.0, 0.0], size: [1.0, 1.0] };
    let scene =
        FiberScene::new(&fibers, &SceneOptions { period: Some(per), backing_z: None }).unwrap();
    assert_eq!(scene.segment_count(), 2, "the original and its copy at x − 1");
    let down = [0.0, 0.0, -1.0];
    for x in [0.02, 7.02, -2.98, 0.9, 0.95] {
        let h = scene.intersect([x, 0.5, 1.0], down, f64::INFINITY, None).expect("hit");
        let dx = (x - 0.95f64 + 0.5).rem_euclid(1.0) - 0.5;
        let want = 1.0 - (0.01 - dx * dx).sqrt();
        assert!((h.t - want).abs() < 1e-6, "x = {x}: t = {} vs {want}", h.t);
        let world = scene.world(h.position, h.shift);
        assert!((world[0] - x).abs() < 1e-9 && (world[1] - 0.5).abs() < 1e-9, "{world:?}");
    }
    assert!(scene.intersect([0.5, 0.5, 1.0], down, f64::INFINITY, None).is_none());
    // A shallow ray descending at 2° towards +x from above the slab crosses several
    // tiles; brute force over translated copies says where it lands.
    let d = vec3::normalize([1.0, 0.0, -(2f64.to_radians().tan())]).unwrap();
    let o = [0.5, 0.5, 0.3];
    let h = scene.intersect(o, d, f64::INFINITY, None).unwrap();
    let want = (-2..12)
        .filter_map(|k| {
            let x = 0.95 + k as f64;
            entry([x, 0.1, 0.0], [x, 0.9, 0.0], 0.1, o, d, 0.0, 100.0).map(|e| e.t)
        })
        .fold(f64::INFINITY, f64::min);
    assert!((h.t - want).abs() < 1e-6, "{} vs {want} (f32 geometry)", h.t);
    let w = scene.world(h.position, h.shift);
    assert!(
        vec3::distance(w, vec3::add_scaled(o, d, want)) < 1e-6 && h.shift[0] >= 5,
        "{w:?} {:?}",
        h.shift
    );
    // The backing plane ends a ray through the gap.
    let scene =
        FiberScene::new(&fibers, &SceneOptions { period: Some(per), backing_z: Some(-0.5) })
            .unwrap();
    let h = scene.intersect([0.5, 0.5, 1.0], down, f64::INFINITY, None).unwrap();
    assert_eq!(h.kind, HitKind::Backing);
    assert!((h.t - 1.5).abs() < 1e-12);
    assert!(scene.occluded([0.5, 0.5, 1.0], down, f64::INFINITY, None));
    assert!(!scene.occluded([0.5, 0.5, 1.0], [0.0, 0.0, 1.0], f64::INFINITY, None));
}

#[test]
fn rays_leaving_a_fiber_axis_skip_their_own_fiber() {
    // A bent fiber: from its axis, a ray along the next segment would enter that capsule
    // at the joint; the skip rule ignores it, but another fiber is still seen.
    let bent = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.3, 0.0], [3.0, 0.9, 0.0]];
    let other = vec![[2.5, -1.0, 0.0], [2.5, 1.0, 0.0]];
    let fibers = fibers_from_polylines(&[bent, other], 0.05, [1.0; 3]);
    let scene = FiberScene::new(&fibers, &SceneOptions::default()).unwrap();
    let sp = scene.surface(0, 0.9, [0.9, 0.0, 0.05]);
    let d = vec3::normalize([1.0, 0.25, 0.0]).unwrap();
    let h = scene.intersect(sp.axis_point, d, f64::INFINITY, Some(sp.skip)).unwrap();
    let HitKind::Fiber { segment, .. } = h.kind else { panic!() };
    assert_eq!(scene.surface(segment, 0.5, h.position).fiber, 1);
    // Tangent is interpolated between vertex tangents and unit.
    assert!((vec3::length(sp.tangent) - 1.0).abs() < 1e-12 && sp.tangent[1] > 0.0);
}

#[test]
fn bad_fibers_are_refused_naming_the_fiber_and_point() {
    let mut f = fibers_from_polylines(
        &[vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![[0.0; 3], [0.0, 1.0, 0.0]]],
        0.1,
        [1.0; 3],
    );
    f.points[3][1] = f32::NAN;
    let e = FiberScene::new(&f, &SceneOptions::default()).unwrap_err().to_string();
    assert!(e.contains("fiber 1") && e.contains("point 1"), "{e}");
    let mut f = fibers_from_polylines(&[vec![[0.0; 3], [1.0, 0.0, 0.0]]], 0.1, [1.0; 3]);
    f.radii[0] = -1.0;
    assert!(
        FiberScene::new(&f, &SceneOptions::default()).unwrap_err().to_string().contains("fiber 0")
    );
    // Zero radius: no capsule, no NaN, nothing hit.
    let f = fibers_from_polylines(&[vec![[0.0; 3], [1.0, 0.0, 0.0]]], 0.0, [1.0; 3]);
    let s = FiberScene::new(&f, &SceneOptions::default()).unwrap();
    assert!(s.intersect([0.5, 0.0, 1.0], [0.0, 0.0, -1.0], f64::INFINITY, None).is_none());
}
