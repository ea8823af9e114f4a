use super::*;
use crate::settings::{AoSettings, CoreSettings, ShadowSettings};

/// Small sizes: a bake in well under a second in debug.
fn small() -> BakeSettings {
    let d = BakeSettings::default();
    BakeSettings {
        density_res: 32,
        density_samples: 32,
        core: CoreSettings { width: 64, height: 16, supersample: 2, ..d.core },
        shadow: ShadowSettings { res: 16, slices: 4, steps_per_texel: 2 },
        ao: AoSettings { res: 16, directions: 16, radial_bins: 8 },
        ambient_entries: 32,
        ..d
    }
}

fn cotton() -> YarnParams {
    YarnParams::preset("cotton-2ply").unwrap()
}

#[test]
fn cache_round_trip_and_corruption_is_rebuilt() {
    let dir = tempfile::tempdir().unwrap();
    let (p, s) = (cotton(), small());
    let a = Precomputed::for_params(&p, &s, Some(dir.path())).unwrap();
    assert!(!a.from_cache);
    let b = Precomputed::for_params(&p, &s, Some(dir.path())).unwrap();
    assert!(b.from_cache);
    assert_eq!(
        Precomputed { times: a.times, from_cache: true, ..b.clone() },
        a.clone().with_cache_flag()
    );
    let path = Precomputed::cache_path(dir.path(), &p, &s).unwrap();
    let good = std::fs::read(&path).unwrap();
    // A flipped payload byte, a truncated file and a foreign key are rebuilt, never used.
    let mut flipped = good.clone();
    let k = flipped.len() - 100;
    flipped[k] ^= 0x40;
    let mut foreign = good.clone();
    let key_at = 16 + Precomputed::cache_key(&p, &s).unwrap().find("fiber_radius").unwrap();
    foreign[key_at] = b'X';
    for bad in [flipped, good[..good.len() / 2].to_vec(), foreign, b"YPRECMP\0".to_vec()] {
        std::fs::write(&path, &bad).unwrap();
        let c = Precomputed::for_params(&p, &s, Some(dir.path())).unwrap();
        assert!(!c.from_cache);
        assert_eq!(c.core, a.core);
        assert_eq!(std::fs::read(&path).unwrap(), good, "the cache file is rewritten");
    }
    // Other settings or parameters: another file.
    let mut s2 = s;
    s2.ao.directions = 17;
    assert_ne!(Precomputed::cache_path(dir.path(), &p, &s2).unwrap(), path);
    let mut p2 = p.clone();
    p2.fiber_radius *= 1.0 + 1e-12;
    assert_ne!(Precomputed::cache_path(dir.path(), &p2, &s).unwrap(), path);
}

impl Precomputed {
    fn with_cache_flag(self) -> Self {
        Precomputed { from_cache: true, ..self }
    }
}

#[test]
fn bad_settings_are_refused_with_the_field_named() {
    type Edit = fn(&mut BakeSettings);
    let cases: [(&str, Edit); 7] = [
        ("core.width", |s| s.core.width = 0),
        ("core.supersample", |s| s.core.supersample = 0),
        ("shadow.slices", |s| s.shadow.slices = 1),
        ("ao.directions", |s| s.ao.directions = 0),
        ("shadow.res² × shadow.slices", |s| {
            s.shadow.res = 4096;
            s.shadow.slices = 1024
        }),
        ("core.width × core.height", |s| {
            s.core.width = 1 << 16;
            s.core.height = 1 << 16
        }),
        ("ao.res² × ao.directions", |s| {
            s.ao.res = 4096;
            s.ao.directions = 1 << 16
        }),
    ];
    for (field, edit) in cases {
        let mut s = small();
        edit(&mut s);
        let msg = Precomputed::for_params(&cotton(), &s, None).unwrap_err().to_string();
        assert!(msg.contains(field), "{field}: {msg}");
    }
}

#[test]
fn hard_cases_bake_finite_textures() {
    type Edit = fn(&mut YarnParams);
    let cases: [(&str, Edit); 5] = [
        ("r_f = 0", |p| p.fiber_radius = 0.0),
        ("rho_min = rho_max", |p| p.rho_min = p.rho_max),
        ("s = 0", |p| p.migration_rate = 0.0),
        ("n_ply = 1", |p| p.ply_count = 1),
        ("no core", |p| p.core_fraction = 0.0),
    ];
    for (name, edit) in cases {
        let mut p = cotton();
        edit(&mut p);
        let b = Precomputed::bake(&p, &small()).unwrap();
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        assert!(finite(&b.core.tex_a) && finite(&b.core.tex_b), "{name}");
        assert!(finite(&b.self_shadow.depth) && finite(&b.ao_texture.ao), "{name}");
        assert!(b.ao_cubic.coeffs.iter().all(|c| c.is_finite()), "{name}");
        let cover = b.core.tex_a.chunks(4).map(|t| t[0] as f64).sum::<f64>();
        match name {
            "r_f = 0" => {
                assert!(b.self_shadow.depth.iter().all(|d| *d == 0.0), "{name}");
                assert!(b.ao_texture.ao.iter().all(|a| *a == 1.0), "{name}");
                assert_eq!(b.self_shadow.transmittance_for_light(0.0, 0.0, [0.0, 0.0, 1.0]), 1.0);
                assert_eq!(cover, 0.0, "{name}: fibers of no thickness cover nothing");
            }
            "no core" => assert_eq!((b.core.core_fibers, cover), (0, 0.0), "{name}"),
            _ => assert!(cover > 0.0, "{name}: the core is built"),
        }
    }
}
