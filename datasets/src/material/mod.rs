//! Synthetic mesostructure materials: a BTF rendered from a periodic height field with
//! spatially varying albedo (DESIGN.md §5), with known ground truth.
//!
//! For every view slot, light and texel the value is (Sattler et al. 2003 §3 define the
//! BTF; the radiometry is DESIGN.md §3): `BTF(x, v, l) = f(n, v, l; ρ) · max(0, n·l) · T`,
//! evaluated at the point where the view ray through texel `x` of the reference plane
//! really meets the relief (parallax, masking), with `T` the transmittance of the light ray
//! from that point (self-shadowing) and `f` the local model of [`brdf`]. A flat Lambertian
//! sample gives exactly `ρ(x)/π · cos θ_l`. Lights at or below the horizon give 0.
//!
//! Submodules: [`brdf`] (local reflection), [`surface`] (height field and ray marches),
//! [`patterns`] and [`knit`] (the kinds), [`generate`] (the parallel, resumable writer) and
//! [`preview`] (contact sheets).

pub mod brdf;
pub mod generate;
pub mod knit;
pub mod patterns;
pub mod preview;
pub mod surface;
pub mod weave_lambert;

pub use generate::{GenerateOptions, GenerateReport, generate};

use crate::vec3::{dot, normalize_or};
use crate::{Error, Result};
use brdf::{Brdf, BrdfParams};
use serde::{Deserialize, Serialize};
use surface::{Hit, Surface};

/// The closed set of synthetic material kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MaterialKind {
    /// Flat Lambertian sample with a patterned albedo: the analytic validation case.
    Lambert,
    /// Corduroy: rounded wales along `+y` with a sheen pile (anisotropic).
    Corduroy,
    /// Stockinette knit: yarn tubes from a stitch skeleton (Chen et al. 2003 §3).
    Knit,
    /// Plain weave of two yarn colours.
    Woven,
    /// Embossed glossy paint.
    Wallpaper,
    /// Fractal stone relief.
    Stone,
}

impl MaterialKind {
    /// All kinds, in a fixed order.
    pub const ALL: [MaterialKind; 6] = [
        MaterialKind::Lambert,
        MaterialKind::Corduroy,
        MaterialKind::Knit,
        MaterialKind::Woven,
        MaterialKind::Wallpaper,
        MaterialKind::Stone,
    ];

    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            MaterialKind::Lambert => "lambert",
            MaterialKind::Corduroy => "corduroy",
            MaterialKind::Knit => "knit",
            MaterialKind::Woven => "woven",
            MaterialKind::Wallpaper => "wallpaper",
            MaterialKind::Stone => "stone",
        }
    }

    /// Parses a lower-case name.
    pub fn from_name(name: &str) -> Result<Self> {
        MaterialKind::ALL.into_iter().find(|k| k.name() == name).ok_or_else(|| {
            let known: Vec<_> = MaterialKind::ALL.iter().map(|k| k.name()).collect();
            Error::Invalid(format!("unknown material kind '{name}' (known: {})", known.join(", ")))
        })
    }

    /// Default pattern period in texels (the number of repeats follows from the size).
    fn default_period_texels(self) -> f64 {
        match self {
            MaterialKind::Lambert | MaterialKind::Knit | MaterialKind::Corduroy => 16.0,
            MaterialKind::Woven => 8.0,
            MaterialKind::Wallpaper => 32.0,
            MaterialKind::Stone => 64.0,
        }
    }
}

/// Parameters of a kind; [`MaterialParams::default_for`] gives sensible ones.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MaterialParams {
    /// Pattern repeats across the texture (ribs, stitch columns, threads, motifs).
    pub repeats: u32,
    /// Relief height as a fraction of one pattern period (knit: ignored, the yarn radius
    /// sets it).
    pub relief: f64,
    /// Main albedo (linear RGB, each in `[0, 1]`).
    pub base_albedo: [f64; 3],
    /// Second albedo (woven weft, wallpaper motif; unused elsewhere).
    pub second_albedo: [f64; 3],
    /// Local reflection model.
    pub brdf: BrdfParams,
    /// Angular radius (radians) of the disc over which shadows are softened: small for
    /// solid relief, larger for fuzzy fibre surfaces.
    pub shadow_softness: f64,
    /// How much the shading normal is pulled towards the sample normal (0 = geometric
    /// normal, 1 = flat): upright pile fibres on corduroy and velvet.
    pub pile_normal_bias: f64,
}

impl MaterialParams {
    /// Defaults for `kind` at `size²` texels.
    pub fn default_for(kind: MaterialKind, size: usize) -> Self {
        use MaterialKind::*;
        let repeats = ((size as f64 / kind.default_period_texels()).round() as u32).max(1);
        let no_sheen = |f0: f64, a: f64| BrdfParams {
            spec_f0: f0,
            spec_alpha: a,
            sheen_color: [0.0; 3],
            sheen_roughness: 0.5,
        };
        let sheen = |f0: f64, a: f64, s: f64, r: f64| BrdfParams {
            spec_f0: f0,
            spec_alpha: a,
            sheen_color: [s; 3],
            sheen_roughness: r,
        };
        let (relief, base, second, brdf, shadow_softness, pile_normal_bias) = match kind {
            Lambert => (0.0, [0.7, 0.6, 0.5], [0.0; 3], no_sheen(0.0, 0.5), 0.0, 0.0),
            Corduroy => {
                (0.35, [0.45, 0.28, 0.16], [0.0; 3], sheen(0.02, 0.5, 0.5, 0.35), 0.10, 0.7)
            }
            Knit => (0.0, [0.7, 0.12, 0.1], [0.0; 3], sheen(0.02, 0.6, 0.3, 0.5), 0.08, 0.0),
            Woven => {
                (0.3, [0.15, 0.2, 0.55], [0.85, 0.8, 0.65], sheen(0.04, 0.3, 0.25, 0.4), 0.06, 0.0)
            }
            Wallpaper => {
                (0.04, [0.82, 0.78, 0.66], [0.72, 0.55, 0.25], no_sheen(0.05, 0.2), 0.02, 0.0)
            }
            Stone => (0.06, [0.55, 0.5, 0.45], [0.0; 3], no_sheen(0.04, 0.7), 0.02, 0.0),
        };
        MaterialParams {
            repeats,
            relief,
            base_albedo: base,
            second_albedo: second,
            brdf,
            shadow_softness,
            pile_normal_bias,
        }
    }

    fn validate(&self) -> Result<()> {
        let ok01 = |c: &[f64; 3]| c.iter().all(|&x| x.is_finite() && (0.0..=1.0).contains(&x));
        if !ok01(&self.base_albedo) || !ok01(&self.second_albedo) || !ok01(&self.brdf.sheen_color) {
            return Err(Error::Invalid(
                "albedos and sheen colour must be finite and in [0, 1]".into(),
            ));
        }
        if !(self.relief.is_finite() && (0.0..=2.0).contains(&self.relief)) {
            return Err(Error::Invalid(format!("relief {} is outside [0, 2]", self.relief)));
        }
        if self.repeats == 0 || self.repeats > 4096 {
            return Err(Error::Invalid(format!("repeats {} is outside 1..=4096", self.repeats)));
        }
        let finite = [self.brdf.spec_f0, self.brdf.spec_alpha, self.brdf.sheen_roughness];
        if finite.iter().any(|x| !x.is_finite()) {
            return Err(Error::Invalid("BRDF parameters must be finite".into()));
        }
        if !(0.0..=0.5).contains(&self.shadow_softness)
            || !(0.0..=1.0).contains(&self.pile_normal_bias)
        {
            return Err(Error::Invalid(
                "shadow softness must be in [0, 0.5] rad, pile normal bias in [0, 1]".into(),
            ));
        }
        Ok(())
    }
}

/// What to synthesise: kind, size, sampling, seed and optional overrides.
#[derive(Debug, Clone)]
pub struct MaterialSpec {
    /// Kind of material.
    pub kind: MaterialKind,
    /// Texels per side (the texture is square).
    pub size: usize,
    /// View and light sampling.
    pub sampling: btf_core::Sampling,
    /// Seed of every random choice (noise, loop jitter).
    pub seed: u64,
    /// Overrides the base albedo of the default parameters.
    pub albedo: Option<[f64; 3]>,
    /// Overrides all parameters (then `albedo`, if set, still replaces the base albedo).
    pub params: Option<MaterialParams>,
}

impl MaterialSpec {
    /// A spec with default parameters, `ubo81` sampling and seed 1.
    pub fn new(kind: MaterialKind, size: usize) -> Self {
        MaterialSpec {
            kind,
            size,
            sampling: btf_core::Sampling::ubo81(),
            seed: 1,
            albedo: None,
            params: None,
        }
    }

    /// The parameters that will be used.
    pub fn resolved_params(&self) -> MaterialParams {
        let mut p = self
            .params
            .clone()
            .unwrap_or_else(|| MaterialParams::default_for(self.kind, self.size));
        if let Some(a) = self.albedo {
            p.base_albedo = a;
        }
        p
    }
}

/// A material ready to evaluate: its surface and local reflection model.
#[derive(Debug, Clone)]
pub struct Material {
    kind: MaterialKind,
    params: MaterialParams,
    surface: Surface,
    brdf: Brdf,
}

impl Material {
    /// Builds the mesostructure of `spec` (deterministic in the seed).
    pub fn build(spec: &MaterialSpec) -> Result<Self> {
        if spec.size == 0 || spec.size > 8192 {
            return Err(Error::Invalid(format!("texture size {} is outside 1..=8192", spec.size)));
        }
        let p = spec.resolved_params();
        p.validate()?;
        let (n, seed, r) = (spec.size, spec.seed, p.repeats);
        let period = n as f64 / r as f64;
        let (height, albedo) = if spec.kind == MaterialKind::Knit {
            knit::stockinette(seed, n, r, ((r as f64 * 1.25).round() as u32).max(1), p.base_albedo)
        } else {
            let f: Box<patterns::TexelFn> = match spec.kind {
                MaterialKind::Lambert => {
                    Box::new(|u, v| (0.0, patterns::lambert_albedo(seed, r, p.base_albedo, u, v)))
                }
                MaterialKind::Corduroy => {
                    Box::new(|u, v| patterns::corduroy(seed, r, p.base_albedo, u, v))
                }
                MaterialKind::Woven => {
                    Box::new(|u, v| patterns::woven(seed, r, p.base_albedo, p.second_albedo, u, v))
                }
                MaterialKind::Wallpaper => Box::new(|u, v| {
                    patterns::wallpaper(seed, r, p.base_albedo, p.second_albedo, u, v)
                }),
                _ => Box::new(|u, v| patterns::stone(seed, r, p.base_albedo, u, v, n)),
            };
            let mut h = Vec::with_capacity(n * n);
            let mut a = Vec::with_capacity(n * n);
            for y in 0..n {
                for x in 0..n {
                    let (hh, aa) = f((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64);
                    h.push(hh * p.relief * period);
                    a.push(aa);
                }
            }
            (h, a)
        };
        let surface = Surface::new(n, height, albedo, p.shadow_softness);
        Ok(Material { kind: spec.kind, brdf: Brdf::new(p.brdf), params: p, surface })
    }

    /// The kind.
    pub fn kind(&self) -> MaterialKind {
        self.kind
    }
    /// The parameters in use.
    pub fn params(&self) -> &MaterialParams {
        &self.params
    }
    /// The mesostructure.
    pub fn surface(&self) -> &Surface {
        &self.surface
    }

    /// Where the view ray of every texel meets the surface (row-major), for `view` a unit
    /// tangent-space vector towards the viewer.
    pub fn view_hits(&self, view: [f64; 3]) -> Vec<Hit> {
        let n = self.surface.size();
        (0..n * n).map(|i| self.surface.view_hit(i % n, i / n, view)).collect()
    }

    /// The BTF value at a precomputed hit for view `view` and light `light` (unit
    /// tangent-space vectors towards viewer and light).
    pub fn shade(&self, hit: &Hit, view: [f64; 3], light: [f64; 3]) -> [f64; 3] {
        if light[2] <= 0.0 || view[2] <= 0.0 {
            return [0.0; 3];
        }
        let b = self.params.pile_normal_bias;
        let n = if b > 0.0 {
            let g = hit.normal;
            normalize_or([g[0] * (1.0 - b), g[1] * (1.0 - b), g[2] * (1.0 - b) + b], g)
        } else {
            hit.normal
        };
        let mu_i = dot(n, light);
        if mu_i <= 0.0 || dot(hit.normal, light) <= 0.0 {
            return [0.0; 3];
        }
        let t = self.surface.light_transmittance(hit.pos, light);
        if t <= 0.0 {
            return [0.0; 3];
        }
        self.brdf.eval(n, view, light, hit.albedo).map(|f| f * mu_i * t)
    }

    /// The BTF value at any point `(px, py)` of the reference plane (texel units, texel
    /// `(x, y)` spans `[x, x + 1) × [y, y + 1)`), for unit view and light vectors.
    pub fn eval_at(&self, px: f64, py: f64, view: [f64; 3], light: [f64; 3]) -> [f64; 3] {
        if view[2] <= 0.0 {
            return [0.0; 3];
        }
        self.shade(&self.surface.view_hit_at(px, py, view), view, light)
    }

    /// The BTF value of texel `(x, y)` for any view and light (unit tangent-space vectors).
    pub fn eval(&self, x: usize, y: usize, view: [f64; 3], light: [f64; 3]) -> [f64; 3] {
        if view[2] <= 0.0 {
            return [0.0; 3];
        }
        self.shade(&self.surface.view_hit(x, y, view), view, light)
    }
}
