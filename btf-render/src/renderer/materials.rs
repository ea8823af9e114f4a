//! The materials a scene draws (`[S03 eq. 2–5]` data): each eigen store used by some
//! triangle loaded and packed once (`crate::material`), the decision the pass key needs
//! (a constant group count, `f16` weight rows), and after the BTF pass is built their
//! uploads and bind groups.

use crate::Gpu;
use crate::Result;
use crate::material::{MaterialData, MaterialGpu, SamplingsRaw};
use crate::passes::btf::BtfPass;
use crate::scene::Scene;
use wgpu::util::DeviceExt;

/// Largest group count compiled into the BTF pass as a constant (`BtfPassKey::groups`;
/// BENCHMARKS.md #5 has the measurements behind it). `slot_fixed` in `btf_vertex.wgsl` holds
/// at most four groups in registers, so this must not exceed 4.
const MAX_CONSTANT_GROUPS: usize = 4;
const _: () = assert!(MAX_CONSTANT_GROUPS <= 4, "slot_fixed holds at most four groups");

/// One uploaded material.
struct Uploaded {
    _gpu: MaterialGpu,
    bind_group: wgpu::BindGroup,
}

/// The scene's used materials, by slot.
pub(crate) struct Materials {
    /// Packed data per slot.
    data: Vec<MaterialData>,
    /// Scene material (`[[materials]]` index) of each slot.
    used: Vec<usize>,
    /// Slot of each scene material (`usize::MAX`: unused).
    slot_of_desc: Vec<usize>,
    /// Constant group count of the pass (0: each material's own at run time).
    groups: u32,
    /// `f16` weight rows per slot, when every material's fit (before upload).
    packed: Option<Vec<Vec<[u32; 4]>>>,
    packed_weights: bool,
    uploaded: Vec<Uploaded>,
    bytes: u64,
}

impl Materials {
    /// Loads every material some triangle uses (`tri_desc[t]`: the scene material of
    /// triangle `t`), each once.
    pub fn load(scene: &Scene, tri_desc: &[usize]) -> Result<Materials> {
        let mut used: Vec<usize> = tri_desc.to_vec();
        used.sort_unstable();
        used.dedup();
        let mut slot_of_desc = vec![usize::MAX; scene.materials.len()];
        let mut data = Vec::new();
        for &d in &used {
            slot_of_desc[d] = data.len();
            data.push(MaterialData::load(&scene.materials[d].store, scene.effects.components)?);
        }
        let groups = match data.first() {
            Some(first) if data.iter().all(|d| d.groups == first.groups) => first.groups,
            _ => 0,
        };
        // a constant group count up to 4 (c ≤ 16); beyond, llvmpipe runs the loop faster
        let groups = if groups <= MAX_CONSTANT_GROUPS { groups as u32 } else { 0 };
        // f16 weight rows where every material's fit (else all keep f32 rows)
        let packed: Option<Vec<Vec<[u32; 4]>>> =
            if groups > 0 { data.iter().map(|d| d.packed_weights()).collect() } else { None };
        Ok(Materials {
            data,
            used,
            slot_of_desc,
            groups,
            packed_weights: packed.is_some(),
            packed,
            uploaded: Vec::new(),
            bytes: 0,
        })
    }

    /// Uploads every material and builds its bind group for `btf`.
    pub fn upload(&mut self, gpu: &Gpu, scene: &Scene, btf: &BtfPass) -> Result<()> {
        let fx = &scene.effects;
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("btf texels"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: if fx.mipmaps { fx.anisotropy } else { 1 },
            ..Default::default()
        });
        let packed = self.packed.take();
        for (k, data) in self.data.iter().enumerate() {
            let desc = &scene.materials[self.used[k]];
            let gpu_mat = MaterialGpu::upload_with(
                gpu,
                data,
                &desc.store.display().to_string(),
                fx.mipmaps,
                packed.as_ref().map(|p| p[k].as_slice()),
            )?;
            self.bytes += gpu_mat.bytes;
            let samplings = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("samplings"),
                contents: bytemuck::bytes_of(&SamplingsRaw::of_material(data, desc.uv_scale)),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind_group = btf.material_bind_group(gpu, &gpu_mat, &samplings, &sampler);
            self.uploaded.push(Uploaded { _gpu: gpu_mat, bind_group });
        }
        Ok(())
    }

    /// The pass's constant group count (0: run time).
    pub fn constant_groups(&self) -> u32 {
        self.groups
    }

    /// Whether the weights are uploaded in the packed `f16` layout.
    pub fn packed(&self) -> bool {
        self.packed_weights
    }

    /// Packed data of every slot.
    pub fn data(&self) -> &[MaterialData] {
        &self.data
    }

    /// Scene material (`[[materials]]` index) of slot `k`.
    pub fn scene_index(&self, k: usize) -> usize {
        self.used[k]
    }

    /// Slot of each scene material (`usize::MAX`: unused).
    pub fn slot_of_desc(&self) -> &[usize] {
        &self.slot_of_desc
    }

    /// Bind group (group 1) of slot `k`.
    pub fn bind_group(&self, k: usize) -> &wgpu::BindGroup {
        &self.uploaded[k].bind_group
    }

    /// Bytes of material data on the GPU.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Largest group count over the materials (the per-vertex layout's stride).
    pub fn max_groups(&self) -> usize {
        self.data.iter().map(|m| m.groups).max().unwrap_or(1)
    }

    /// Components the materials use (the smallest over materials).
    pub fn components(&self) -> usize {
        self.data.iter().map(|m| m.components).min().unwrap_or(0)
    }

    /// The view sampling of every slot.
    pub fn view_samplings(&self) -> Vec<&btf_core::Sampling> {
        self.data.iter().map(|m| &m.view_sampling).collect()
    }
}
