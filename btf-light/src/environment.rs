//! An environment light of a scene at run time (`[S03 §5.3–5.4]`): the
//! visibility maps of the mesh, the gathered radiances `g` of the current environment and
//! rotation and optionally the eigenweightsets; [`crate::EnvCoefficients`] turns them into
//! the per-vertex coefficients `f · ω_m · γ*_{k j_m}` a camera needs (eq. 11).
//!
//! Visibility is computed once per mesh and resolution (and cached on disk when a cache
//! folder is given), for every frame or only for those a fixed camera shows
//! ([`SceneEnvironment::with_frames`]; the rest on demand: [`SceneEnvironment::complete`]).
//! A new environment costs one gather (eq. 10) and, with eigenweightsets, one PCA over `A`
//! rotations, after which a rotation costs `e` vector additions (eq. 13). Back sides of two-sided cloth have hemicubes of their own.

use crate::coefficients::CoefficientMatrix;
use crate::eigenweights::EigenWeightSets;
use crate::env_cube::EnvCube;
use crate::gather::{GatherInput, Radiances, rotate_z};
use crate::hemicube::{Hemicube, HemicubeFrame, LightTable, pixel_of};
use crate::visibility::{self, VisibilityMaps};
use crate::{Error, Result};
use btf_core::{InterpMode, Sampling};
use btf_image::EnvMap;
use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Instant;

/// Eigenweightsets kept at least (when on and the rank allows), so that error reports for
/// `e = 1…8` come from the same PCA.
pub const REPORT_COMPONENTS: usize = 8;

/// What an environment light asks for.
#[derive(Debug, Clone)]
pub struct EnvironmentParams {
    /// Rotation of the environment about world `+z`, degrees.
    pub rotation_deg: f64,
    /// Exposure factor `f` (eq. 11).
    pub exposure: f32,
    /// Hemicube resolution (pixels across the top face).
    pub visibility_res: u32,
    /// Separate hemicubes for the back sides of the cloth.
    pub two_sided: bool,
    /// Eigenweightsets: `Some((A rotations, e))`.
    pub eigen: Option<(usize, usize)>,
    /// Folder for the visibility cache (`None`: no caching).
    pub cache_dir: Option<PathBuf>,
}

/// The mesh data the environment needs.
pub struct EnvMesh<'a> {
    /// Positions.
    pub positions: &'a [[f32; 3]],
    /// Unit normals.
    pub normals: &'a [[f32; 3]],
    /// Tangents `[T, s]`.
    pub tangents: &'a [[f32; 4]],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
}

/// Costs of the last preparation steps, milliseconds.
#[derive(Debug, Clone, Copy, Default)]
pub struct EnvTimings {
    /// Finding the vertex sides the camera shows (the renderer's corner-id pass; 0 when
    /// every side is computed).
    pub sides_ms: f64,
    /// Visibility maps (0 when loaded from the cache).
    pub visibility_ms: f64,
    /// Whether the visibility maps came from the cache.
    pub visibility_cached: bool,
    /// Filtering plus gathering `g` for the current environment and rotation.
    pub weights_ms: f64,
    /// Building the eigenweightsets (A gathers and the PCA).
    pub eigen_ms: f64,
    /// Last rotation update (eigenweightset reconstruction or gather).
    pub rotation_ms: f64,
}

/// Runtime state of one environment light.
pub struct SceneEnvironment {
    params: EnvironmentParams,
    cube: Hemicube,
    table: LightTable,
    frames: Vec<HemicubeFrame>,
    vertices: usize,
    lights: usize,
    vis: VisibilityMaps,
    /// The frames whose visibility was computed (`None`: all); the others are zero.
    wanted: Option<Vec<bool>>,
    coefficients: Vec<CoefficientMatrix>,
    env: EnvCube,
    /// `G` of the current rotation (formed on first use after an eigenweightset rotation).
    radiances: OnceLock<Radiances>,
    /// `o_k(δ)` of the current rotation when it came from the eigenweightsets.
    eigen_o: Option<Vec<f64>>,
    eigen: Option<EigenWeightSets>,
    /// Counts [`SceneEnvironment::set_environment`] calls (caches keyed on the map).
    revision: u64,
    /// Timings of the preparation.
    pub timings: EnvTimings,
}

impl SceneEnvironment {
    /// Computes (or loads) the visibility maps and gathers the radiances of `env` for
    /// materials of the light sampling `lights` with the coefficient matrices
    /// `coefficients` (one per material, [`CoefficientMatrix`]).
    pub fn new(
        params: EnvironmentParams,
        env: &EnvMap,
        mesh: &EnvMesh,
        lights: &Sampling,
        coefficients: Vec<CoefficientMatrix>,
    ) -> Result<Self> {
        Self::with_frames(params, env, mesh, lights, coefficients, None)
    }

    /// Whether the visibility cache of `params` already holds every frame of `mesh` — then
    /// [`SceneEnvironment::with_frames`] takes them all and the frames a camera shows need
    /// not be found.
    pub fn cache_holds_all(params: &EnvironmentParams, mesh: &EnvMesh) -> Result<bool> {
        let Some(dir) = &params.cache_dir else { return Ok(false) };
        let cube = Hemicube::new(params.visibility_res)?;
        let frames =
            HemicubeFrame::of_mesh(mesh.positions, mesh.normals, mesh.tangents, params.two_sided);
        let key = visibility::cache_key(cube.res, &frames, mesh.triangles);
        Ok(visibility::cache_path(dir, key).is_file())
    }

    /// [`SceneEnvironment::new`] with visibility only for the frames `wanted` flags (front
    /// sides `0..V`, back sides `V..2V`): the vertex sides a fixed camera shows (finding
    /// them is the caller's, and its time goes to [`EnvTimings::sides_ms`]; when the cache
    /// holds every frame, [`SceneEnvironment::cache_holds_all`], all are taken anyway).
    /// Every other frame is left all-occluded, so its radiances are zero;
    /// [`SceneEnvironment::complete`] computes them when another camera needs them.
    pub fn with_frames(
        params: EnvironmentParams,
        env: &EnvMap,
        mesh: &EnvMesh,
        lights: &Sampling,
        coefficients: Vec<CoefficientMatrix>,
        wanted: Option<Vec<bool>>,
    ) -> Result<Self> {
        if coefficients.is_empty() {
            return Err(Error::Invalid("environment light without materials".into()));
        }
        if let Some(c) = coefficients.iter().find(|c| c.lights != lights.len()) {
            return Err(Error::Invalid(format!(
                "a coefficient matrix of {} lights for a sampling of {}",
                c.lights,
                lights.len()
            )));
        }
        let cube = Hemicube::new(params.visibility_res)?;
        let table = LightTable::new(&cube, lights, InterpMode::Four)?;
        let frames =
            HemicubeFrame::of_mesh(mesh.positions, mesh.normals, mesh.tangents, params.two_sided);
        if let Some(w) = &wanted
            && w.len() != frames.len()
        {
            return Err(Error::Invalid(format!(
                "{} wanted flags for {} hemicube frames",
                w.len(),
                frames.len()
            )));
        }
        let mut wanted = wanted.filter(|w| !w.iter().all(|&x| x));
        let t = Instant::now();
        let (pos, tris) = (mesh.positions, mesh.triangles);
        let (vis, cached, all) = match (&params.cache_dir, &wanted) {
            (Some(dir), w) => {
                VisibilityMaps::cached_some(dir, &cube, &frames, w.as_deref(), pos, tris)?
            }
            (None, Some(w)) => {
                (VisibilityMaps::compute_some(&cube, &frames, w, pos, tris), false, false)
            }
            (None, None) => (VisibilityMaps::compute(&cube, &frames, pos, tris), false, true),
        };
        if all {
            wanted = None; // the cache held every frame
        }
        let timings =
            EnvTimings { visibility_ms: ms(t), visibility_cached: cached, ..Default::default() };
        let env_cube = EnvCube { res: 1, dirs: vec![], power: vec![] };
        let mut s = SceneEnvironment {
            params,
            cube,
            table,
            frames,
            vertices: mesh.positions.len(),
            lights: lights.len(),
            vis,
            wanted,
            coefficients,
            env: env_cube,
            radiances: OnceLock::new(),
            eigen_o: None,
            eigen: None,
            revision: 0,
            timings,
        };
        s.set_environment(env)?;
        Ok(s)
    }

    /// Cube resolution the environment is binned to for hemicube resolution `res`: texels
    /// as large as the top face's pixels (finer texels only cost time: each source is
    /// dropped into one pixel anyway).
    pub fn cube_res(res: u32) -> usize {
        (res as usize).max(1)
    }

    /// The exact radiances for rotation `delta_deg` (a full gather, eq. 10), whatever the
    /// eigenweightset setting.
    pub fn gather(&self, delta_deg: f64) -> Radiances {
        let input = GatherInput {
            table: &self.table,
            visibility: &self.vis,
            frames: &self.frames,
            dirs: &self.cube.dirs,
            lights: self.lights,
        };
        Radiances::gather(&input, &self.env, delta_deg)
    }

    /// Switches to a new environment map (keeps rotation and exposure).
    pub fn set_environment(&mut self, env: &EnvMap) -> Result<()> {
        let t = Instant::now();
        self.env = EnvCube::new(env, Self::cube_res(self.params.visibility_res));
        self.prepare_weights(t)
    }

    /// Frames whose visibility was computed, of [`SceneEnvironment::frames`].
    pub fn computed_frames(&self) -> usize {
        self.wanted.as_ref().map_or(self.frames.len(), |w| w.iter().filter(|&&x| x).count())
    }

    /// Hemicube frames of the mesh (`V`, or `2V` when two-sided).
    pub fn frames(&self) -> usize {
        self.frames.len()
    }

    /// Whether frame `f`'s visibility was computed.
    pub fn has_frame(&self, f: usize) -> bool {
        self.wanted.as_ref().is_none_or(|w| w[f])
    }

    /// Computes the visibility of every frame left out by [`SceneEnvironment::with_frames`]
    /// and gathers the weights again (with the eigenweightsets when on): what a camera move
    /// needs when the new camera may show other vertex sides. Returns whether there was
    /// anything to compute. `mesh` must be the mesh the environment was built for.
    pub fn complete(&mut self, mesh: &EnvMesh) -> Result<bool> {
        let Some(wanted) = self.wanted.take() else { return Ok(false) };
        let t = Instant::now();
        let rest: Vec<bool> = wanted.iter().map(|w| !w).collect();
        let more = VisibilityMaps::compute_some(
            &self.cube,
            &self.frames,
            &rest,
            mesh.positions,
            mesh.triangles,
        );
        self.vis.merge_from(&more, &rest);
        if let Some(dir) = &self.params.cache_dir {
            let key = visibility::cache_key(self.vis.res, &self.frames, mesh.triangles);
            self.vis.write(&visibility::cache_path(dir, key))?;
        }
        self.timings.visibility_ms += ms(t);
        self.prepare_weights(Instant::now())?;
        Ok(true)
    }

    /// Gathers `g` of the current environment (and builds its eigenweightsets when on).
    fn prepare_weights(&mut self, t: Instant) -> Result<()> {
        self.revision += 1;
        self.set_weights(self.gather(self.params.rotation_deg));
        self.timings.weights_ms = ms(t);
        self.eigen = None;
        if let Some((a_n, e)) = self.params.eigen {
            let t = Instant::now();
            let sets: Vec<Radiances> =
                (0..a_n).map(|a| self.gather(a as f64 * 360.0 / a_n as f64)).collect();
            let metric = self.coefficients[0].metric();
            // Keep up to REPORT_COMPONENTS so error tables for e = 1…8 need no second PCA.
            let keep = e.max(REPORT_COMPONENTS).min(a_n - 1);
            self.eigen = Some(EigenWeightSets::build(&sets, &metric, keep)?);
            self.timings.eigen_ms = ms(t);
            self.set_rotation(self.params.rotation_deg);
        }
        Ok(())
    }

    /// Rotation in use, degrees.
    pub fn rotation_deg(&self) -> f64 {
        self.params.rotation_deg
    }

    /// Eigenweightsets in use `(A, e)`, when on.
    pub fn eigen_params(&self) -> Option<(usize, usize)> {
        self.params.eigen
    }

    /// Turns the environment to `delta_deg` with the exact weights (one full gather),
    /// whatever the eigenweightset setting — the reference of error measures.
    pub fn set_rotation_exact(&mut self, delta_deg: f64) {
        let t = Instant::now();
        self.params.rotation_deg = delta_deg;
        self.set_weights(self.gather(delta_deg));
        self.timings.rotation_ms = ms(t);
    }

    /// Exact radiances `g` for the current rotation.
    fn set_weights(&mut self, g: Radiances) {
        self.radiances = OnceLock::from(g);
        self.eigen_o = None;
    }

    /// The current rotation through the eigenweightsets: `o_k(δ)`, `G` formed on demand.
    fn set_eigen_rotation(&mut self, delta_deg: f64, e: usize) {
        self.params.rotation_deg = delta_deg;
        self.eigen_o = self.eigen.as_ref().map(|ews| ews.coefficients_at(delta_deg, e));
        self.radiances = OnceLock::new();
    }

    /// `o_k(δ)` of the current rotation, when it came from the eigenweightsets.
    pub fn eigen_coefficients(&self) -> Option<&[f64]> {
        self.eigen_o.as_deref()
    }

    /// Turns the environment to `delta_deg` with `e` eigenweightsets (at most those kept);
    /// an error when eigenweightsets are off.
    pub fn set_rotation_eigen(&mut self, delta_deg: f64, e: usize) -> Result<()> {
        if self.eigen.is_none() {
            return Err(Error::Invalid(
                "eigenweightsets are off for this environment light".into(),
            ));
        }
        let t = Instant::now();
        self.set_eigen_rotation(delta_deg, e);
        self.timings.rotation_ms = ms(t);
        Ok(())
    }

    /// Turns the environment to `delta_deg` about world `+z`: with eigenweightsets the
    /// coefficients `o_k(δ)` (`G` and `γ*` follow on demand, see
    /// [`crate::EnvCoefficients::fill`]), else a new gather.
    pub fn set_rotation(&mut self, delta_deg: f64) {
        let t = Instant::now();
        match (&self.eigen, self.params.eigen) {
            (Some(_), Some((_, e))) => self.set_eigen_rotation(delta_deg, e),
            _ => {
                self.params.rotation_deg = delta_deg;
                self.set_weights(self.gather(delta_deg));
            }
        }
        self.timings.rotation_ms = ms(t);
    }

    /// Sets the exposure `f`.
    pub fn set_exposure(&mut self, f: f32) {
        self.params.exposure = f;
    }

    /// Exposure factor `f` in use.
    pub fn exposure(&self) -> f32 {
        self.params.exposure
    }

    /// Whether the back sides have hemicubes of their own (frames `V + v`).
    pub fn two_sided(&self) -> bool {
        self.params.two_sided
    }

    /// Vertices of the mesh (front frames `0..V`).
    pub fn vertices(&self) -> usize {
        self.vertices
    }

    /// `∫ L_env dω` per channel of the current map (before the exposure; rotation does not
    /// change it).
    pub fn total_power(&self) -> [f64; 3] {
        self.env.total()
    }

    /// Changes with every new environment map (not with rotation or exposure).
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Calls `visit(tangent direction, power)` for every source of the current
    /// environment and rotation that lies above frame `f`'s horizon and falls into a
    /// visible pixel of its hemicube — the terms of eq. 10 before the pixel → light table
    /// (power `∫ L dω` of the source, without the exposure).
    pub fn visible_sources(&self, f: usize, mut visit: impl FnMut([f32; 3], [f32; 3])) {
        let (sin, cos) = self.params.rotation_deg.to_radians().sin_cos();
        let [t, b, n] = self.frames[f].axes.map(|a| rotate_z(a, cos as f32, sin as f32));
        let bits = self.vis.frame_bits(f);
        let res = self.vis.res as usize;
        let dot = |d: &[f32; 3], a: [f32; 3]| d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
        for (d, pw) in self.env.dirs.iter().zip(&self.env.power) {
            let z = dot(d, n);
            if z <= 0.0 {
                continue;
            }
            let (x, y) = (dot(d, t), dot(d, b));
            let p = pixel_of(res, x, y, z);
            if bits[p / 64] >> (p % 64) & 1 == 1 {
                visit([x, y, z], *pw);
            }
        }
    }

    /// The current radiances `g` (after an eigenweightset rotation `Ḡ + Σ o_k W_k`,
    /// formed on the first call).
    pub fn radiances(&self) -> &Radiances {
        self.radiances.get_or_init(|| match (&self.eigen, &self.eigen_o) {
            (Some(ews), Some(o)) => ews.reconstruct_from(o),
            _ => Radiances { frames: self.frames.len(), lights: self.lights, g: vec![] },
        })
    }

    /// The coefficient matrices `P` of the materials (eq. 10–12), in the order given.
    pub fn coefficients(&self) -> &[CoefficientMatrix] {
        &self.coefficients
    }

    /// The visibility maps.
    pub fn visibility(&self) -> &VisibilityMaps {
        &self.vis
    }

    /// The hemicube.
    pub fn hemicube(&self) -> &Hemicube {
        &self.cube
    }

    /// The eigenweightsets, when built.
    pub fn eigenweightsets(&self) -> Option<&EigenWeightSets> {
        self.eigen.as_ref()
    }

    /// The `U` metric of material 0 (for error measures).
    pub fn metric(&self) -> Vec<f64> {
        self.coefficients[0].metric()
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
