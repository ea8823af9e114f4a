//! The thin-cloth pass: draws the triangles of transmissive materials after the opaque
//! BTF geometry, sorted back to front every frame, with `L = L_dst · e^{−τ₁/μ} + L_src`
//! (`[TC eq. 9]`; the shading, `[TC eq. 7–8]`, is in `transmission.wgsl`).
//!
//! Depth is tested against the opaque geometry but not written, so layers behind a thin
//! sheet stay visible. Bind groups 0 and 1 are the BTF pass's (frame, material); group 2,
//! with an environment light, its per-vertex coefficients (the BTF's environment term);
//! group 3 holds the slab parameters and the τ texture of one material and the
//! per-vertex environment tables of `btf_light::thin_tables`.

use super::pipeline::{pipeline, thin_layout};
use super::thickness::{slab_params, tau_texels};
use crate::bind;
use crate::camera::CameraSetup;
use crate::material::MaterialData;
use crate::passes::btf::{BtfPass, BtfPassKey};
use crate::passes::mesh::CornerVertex;
use crate::scene::TransmissionDesc;
use crate::{Error, Gpu, Result};
use btf_light::thin_tables::{SlabParams, VEC4_PER_VERTEX};
use half::f16;
use wgpu::util::DeviceExt;

/// GPU mirror of `ThinRaw`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ThinRaw {
    /// `τ₁`, Henyey–Greenstein `g`, τ texture bound (1/0), the environment's entry in the
    /// per-vertex layout.
    pub params: [f32; 4],
    /// Albedo `ϖ₀` (RGB), the τ-node scale of the environment tables (`SlabParams::tau`).
    pub albedo: [f32; 4],
}

/// One material's slab parameters on the GPU.
struct ThinMaterial {
    group: wgpu::BindGroup,
    _uniform: wgpu::Buffer,
    _tau: wgpu::Texture,
}

/// A run of sorted triangles of one material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinDraw {
    /// Material slot of the renderer.
    pub material: usize,
    /// First corner in the sorted buffer.
    pub first: u32,
    /// Corners.
    pub count: u32,
}

/// What the pass needs when the scene has an environment light.
#[derive(Debug, Clone, Copy)]
pub struct ThinEnv {
    /// Vertices of the merged mesh (size of the environment tables).
    pub vertices: usize,
    /// Index of the environment in the per-vertex coefficient layout (its light index in
    /// per-vertex mode, 0 in per-pixel mode).
    pub entry: u32,
}

/// Pipeline, per-material parameters and the triangles to sort.
pub struct ThinPass {
    pipeline: wgpu::RenderPipeline,
    materials: Vec<Option<ThinMaterial>>,
    slabs: Vec<Option<SlabParams>>,
    /// Per-vertex environment tables (16 bytes when there is no environment light).
    env_tables: wgpu::Buffer,
    environment: bool,
    /// `(material slot, three corners)` of every thin triangle.
    triangles: Vec<(usize, [CornerVertex; 3])>,
    corners: wgpu::Buffer,
}

impl ThinPass {
    /// Builds the pass for the materials with a `transmission` effect; `descs[slot]` is
    /// the effect of material slot `slot` (`None`: opaque), `corners` the renderer's
    /// corner list with `material_of_triangle` per triangle; `env` when the scene has an
    /// environment light.
    pub fn new(
        gpu: &Gpu,
        btf: &BtfPass,
        key: BtfPassKey,
        descs: &[(Option<&TransmissionDesc>, &MaterialData, String)],
        corners: &[CornerVertex],
        material_of_triangle: &[usize],
        env: Option<ThinEnv>,
    ) -> Result<ThinPass> {
        if key.msaa == 1 && !gpu.device.features().contains(wgpu::Features::FLOAT32_BLENDABLE) {
            return Err(Error::Unsupported(
                "thin cloth blends into the f32 colour target, which this GPU cannot blend; set effects.msaa = 4 (f16 target)".into(),
            ));
        }
        let layout = thin_layout(&gpu.device);
        let pipeline = pipeline(gpu, btf, &layout, key, env.is_some())?;
        let env_tables = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("thin environment tables"),
            size: (env.map_or(1, |e| e.vertices * VEC4_PER_VERTEX).max(1) * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entry = env.map_or(0, |e| e.entry);
        let mut materials = Vec::new();
        let mut slabs = Vec::new();
        for (desc, data, name) in descs {
            let Some(d) = desc else {
                materials.push(None);
                slabs.push(None);
                continue;
            };
            let texels = tau_texels(d, data)?;
            let max_texel = texels.2.iter().map(|t| t.to_f32()).fold(0.0, f32::max);
            let slab = slab_params(d, max_texel);
            let bind = ThinBind { layout: &layout, env_tables: &env_tables, env_entry: entry };
            materials.push(Some(ThinMaterial::new(gpu, &bind, d, &slab, texels, name)?));
            slabs.push(Some(slab));
        }
        let triangles: Vec<(usize, [CornerVertex; 3])> = corners
            .chunks_exact(3)
            .zip(material_of_triangle)
            .filter(|(_, m)| materials[**m].is_some())
            .map(|(c, &m)| (m, [c[0], c[1], c[2]]))
            .collect();
        let corners = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("thin corners (sorted)"),
            size: (triangles.len().max(1) * 3 * std::mem::size_of::<CornerVertex>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(ThinPass {
            pipeline,
            materials,
            slabs,
            env_tables,
            environment: env.is_some(),
            triangles,
            corners,
        })
    }

    /// Slab parameters of material slot `m` (`None`: opaque).
    pub fn slab(&self, m: usize) -> Option<SlabParams> {
        self.slabs.get(m).copied().flatten()
    }

    /// Uploads the per-vertex environment tables of [`btf_light::thin_tables::tables`].
    pub fn write_env_tables(&self, gpu: &Gpu, tables: &[[f32; 4]]) -> Result<()> {
        if !self.environment || (tables.len() * 16) as u64 != self.env_tables.size() {
            return Err(Error::Invalid(format!(
                "thin-cloth environment tables: {} vec4 for a buffer of {} bytes",
                tables.len(),
                self.env_tables.size()
            )));
        }
        gpu.queue.write_buffer(&self.env_tables, 0, bytemuck::cast_slice(tables));
        Ok(())
    }

    /// Whether material slot `m` is drawn by this pass (and not by the opaque one).
    pub fn is_thin(&self, m: usize) -> bool {
        self.materials.get(m).is_some_and(Option::is_some)
    }

    /// Sorts the thin triangles back to front for `camera`, uploads them, and returns
    /// the draws (runs of one material).
    pub fn prepare(&self, gpu: &Gpu, camera: &CameraSetup) -> Vec<ThinDraw> {
        let order = back_to_front(&self.triangles, camera);
        let mut sorted = Vec::with_capacity(order.len() * 3);
        let mut draws: Vec<ThinDraw> = Vec::new();
        for &t in &order {
            let (m, c) = &self.triangles[t];
            match draws.last_mut() {
                Some(d) if d.material == *m => d.count += 3,
                _ => draws.push(ThinDraw { material: *m, first: sorted.len() as u32, count: 3 }),
            }
            sorted.extend_from_slice(c);
        }
        if !sorted.is_empty() {
            gpu.queue.write_buffer(&self.corners, 0, bytemuck::cast_slice(&sorted));
        }
        draws
    }

    /// Records the sorted draws into the BTF render pass (after the opaque geometry);
    /// `vertex_group` is the per-vertex coefficients' group (needed with an environment).
    pub fn draw<'a>(
        &'a self,
        pass: &mut wgpu::RenderPass<'a>,
        frame_group: &'a wgpu::BindGroup,
        vertex_group: Option<&'a wgpu::BindGroup>,
        material_group: impl Fn(usize) -> &'a wgpu::BindGroup,
        draws: &[ThinDraw],
    ) {
        if draws.is_empty() {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, frame_group, &[]);
        if let (true, Some(g)) = (self.environment, vertex_group) {
            pass.set_bind_group(2, g, &[]);
        }
        pass.set_vertex_buffer(0, self.corners.slice(..));
        for d in draws {
            let Some(m) = &self.materials[d.material] else { continue };
            pass.set_bind_group(1, material_group(d.material), &[]);
            pass.set_bind_group(3, &m.group, &[]);
            pass.draw(d.first..d.first + d.count, 0..1);
        }
    }
}

/// Triangle indices ordered from the farthest to the nearest centroid (perspective:
/// distance to the eye; orthographic: depth along the view direction). Exact for layers
/// that do not interpenetrate; ties keep mesh order.
pub fn back_to_front(triangles: &[(usize, [CornerVertex; 3])], camera: &CameraSetup) -> Vec<usize> {
    let depth: Vec<f32> = triangles
        .iter()
        .map(|(_, c)| {
            let p =
                [0, 1, 2].map(|a| (c[0].position[a] + c[1].position[a] + c[2].position[a]) / 3.0);
            match camera.ortho_to_camera {
                Some(d) => -(p[0] * d.x + p[1] * d.y + p[2] * d.z),
                None => {
                    let e = camera.eye;
                    (p[0] - e.x).powi(2) + (p[1] - e.y).powi(2) + (p[2] - e.z).powi(2)
                }
            }
        })
        .collect();
    let mut order: Vec<usize> = (0..triangles.len()).collect();
    order.sort_by(|&a, &b| depth[b].total_cmp(&depth[a]));
    order
}

/// What every material's bind group shares.
struct ThinBind<'a> {
    layout: &'a wgpu::BindGroupLayout,
    env_tables: &'a wgpu::Buffer,
    env_entry: u32,
}

impl ThinMaterial {
    fn new(
        gpu: &Gpu,
        bind: &ThinBind,
        desc: &TransmissionDesc,
        slab: &SlabParams,
        (w, h, texels): (u32, u32, Vec<f16>),
        name: &str,
    ) -> Result<ThinMaterial> {
        let (layout, env_tables, env_entry) = (bind.layout, bind.env_tables, bind.env_entry);
        let a = desc.albedo.rgb();
        let raw = ThinRaw {
            params: [
                desc.tau,
                desc.phase.g(),
                desc.tau_texture.is_some() as u32 as f32,
                env_entry as f32,
            ],
            albedo: [a[0], a[1], a[2], slab.tau as f32],
        };
        gpu.scoped(&format!("uploading the transmission of {name}"), || {
            let uniform = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("thin params"),
                contents: bytemuck::bytes_of(&raw),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let tau = gpu.device.create_texture_with_data(
                &gpu.queue,
                &wgpu::TextureDescriptor {
                    label: Some("tau"),
                    size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::R16Float,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                bytemuck::cast_slice(&texels),
            );
            let view = tau.create_view(&Default::default());
            let group = bind::group(
                &gpu.device,
                "thin material",
                layout,
                &[
                    uniform.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&view),
                    env_tables.as_entire_binding(),
                ],
            );
            ThinMaterial { group, _uniform: uniform, _tau: tau }
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn thin_raw_matches_the_wgsl_struct() {
        assert_eq!(std::mem::size_of::<super::ThinRaw>(), 32);
    }
}
