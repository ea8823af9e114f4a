//! The pieces [`Renderer::new`] assembles: the merged mesh, the camera matrices, the
//! thin-cloth pass, the BTF pass's frame bind group, and per frame the per-vertex
//! coefficients (eq. 2–5 folded per vertex, plus the environment's eq. 11).

use super::*;

/// Merges the scene's meshes and assigns each triangle a scene material index.
pub(super) fn load_meshes(scene: &Scene) -> Result<(Mesh, Vec<usize>)> {
    let mut mesh = Mesh::default();
    let mut tri_desc = Vec::new();
    for desc in &scene.meshes {
        let m = Mesh::load_obj(&desc.path, desc.planar_uv)?;
        let base = mesh.positions.len() as u32;
        let mut mat_of_name = Vec::new();
        for name in &m.material_names {
            let found = scene
                .materials
                .iter()
                .position(|md| md.name.as_deref() == Some(name.as_str()))
                .or_else(|| scene.materials.iter().position(|md| md.name.is_none()));
            let Some(i) = found else {
                let what = if name.is_empty() {
                    "faces without `usemtl`".to_string()
                } else {
                    format!("material '{name}'")
                };
                return Err(Error::Invalid(format!(
                    "{}: {what} has no [[materials]] entry (add one with that name, or one without a name as default)",
                    desc.path.display()
                )));
            };
            mat_of_name.push(i);
        }
        mesh.triangles.extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
        tri_desc.extend(m.triangle_material.iter().map(|&id| mat_of_name[id as usize]));
        mesh.positions.extend(m.positions);
        mesh.normals.extend(m.normals);
        mesh.uvs.extend(m.uvs);
        mesh.repaired_normals += m.repaired_normals;
    }
    Ok((mesh, tri_desc))
}

/// The thin-cloth pass, when some material used has a `transmission` effect.
pub(super) fn thin_pass(
    gpu: &Gpu,
    scene: &Scene,
    btf: &BtfPass,
    key: BtfPassKey,
    materials: &[LoadedMaterial],
    used: &[usize],
    corners: &[CornerVertex],
    order: &[usize],
    slot_of_desc: &[usize],
    tri_desc: &[usize],
    vertices: usize,
) -> Result<Option<ThinPass>> {
    let descs: Vec<_> = materials
        .iter()
        .zip(used)
        .map(|(m, &d)| {
            let desc = &scene.materials[d];
            (desc.transmission.as_ref(), &m.data, desc.store.display().to_string())
        })
        .collect();
    if descs.iter().all(|d| d.0.is_none()) {
        return Ok(None);
    }
    let env = match scene.environment() {
        None => None,
        Some((light, e)) => {
            for (desc, _, name) in &descs {
                if let Some(d) = desc {
                    d.check_environment(name, e.two_sided)?;
                }
            }
            let entry = if key.evaluation == Evaluation::PerVertex { light as u32 } else { 0 };
            Some(ThinEnv { vertices, entry })
        }
    };
    let slot_of_triangle: Vec<usize> = order.iter().map(|&t| slot_of_desc[tri_desc[t]]).collect();
    Ok(Some(ThinPass::new(gpu, btf, key, &descs, corners, &slot_of_triangle, env)?))
}

pub(super) fn frame_bind_group(
    gpu: &Gpu,
    btf: &BtfPass,
    frame: &wgpu::Buffer,
    boundary: &wgpu::Texture,
    shadow: &ShadowInputs,
    counters: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let clamp = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("linear clamp"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let boundary_view = boundary.create_view(&Default::default());
    use wgpu::BindingResource::{Sampler, TextureView};
    crate::bind::group(
        &gpu.device,
        "btf frame",
        &btf.frame_layout,
        &[
            frame.as_entire_binding(),
            TextureView(&boundary_view),
            Sampler(&clamp),
            TextureView(&shadow.masks),
            TextureView(&shadow.maps),
            Sampler(&shadow.compare),
            counters.as_entire_binding(),
        ],
    )
}

impl Renderer {
    pub(super) fn per_vertex_bind_group(
        &self,
        gpu: &Gpu,
        timer: &mut PassTimer,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer, wgpu::BindGroup)> {
        let t = Instant::now();
        let per_vertex = self.scene.effects.evaluation == Evaluation::PerVertex;
        let lights = if per_vertex { self.vertex_lights() } else { Vec::new() };
        let mats: Vec<&MaterialData> = self.materials.iter().map(|m| &m.data).collect();
        let input = VertexEvalInput {
            eye: self.camera.eye,
            ortho_to_camera: self.camera.ortho_to_camera,
            lights: &lights,
            view_mode: self.scene.effects.view_blend,
            light_mode: self.scene.effects.light_interp,
            groups_stride: mats.iter().map(|m| m.groups).max().unwrap_or(1),
            separable: self.btf.key.separable(),
        };
        let mut vc = per_vertex::compute(
            &self.mesh.positions,
            &self.mesh.normals,
            &self.tangents,
            &self.vertex_material,
            &mats,
            &input,
        );
        if per_vertex {
            timer.cpu("per-vertex coefficients (cpu)", t.elapsed().as_secs_f64() * 1e3);
        }
        if let Some(e) = &self.environment {
            let t = Instant::now();
            let samplings = self.view_samplings();
            let view = self.view_input(&samplings);
            let (l, n_lights) = if per_vertex { (e.light, lights.len()) } else { (0, 1) };
            let at = Slots { l, n_lights, stride: per_vertex::stride(input.groups_stride) };
            let mut fill = e.fill.lock().unwrap_or_else(|p| p.into_inner());
            fill.fill(&e.env, &mut vc.coef, &view, at);
            timer.cpu("env coefficients per vertex (cpu)", t.elapsed().as_secs_f64() * 1e3);
        }
        let mk = |label, bytes: &[u8]| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        // f16 where the pass has a constant group count (slot_fixed): the separable scalars
        // as they are where the weight rows fit f16, the full layout with a scale per entry
        let key = self.btf.key;
        let coef = match (key.separable(), key.packed, key.groups > 0) {
            (true, true, _) => per_vertex::pack_scalars_f16(&vc.coef, input.groups_stride),
            (false, _, true) => per_vertex::pack_f16(&vc.coef, input.groups_stride),
            _ => bytemuck::cast_slice(&vc.coef).to_vec(),
        };
        let coef = mk("vertex coefficients", bytemuck::cast_slice(&coef));
        let slots = mk("vertex slots", bytemuck::cast_slice(&vc.slots));
        // (a binding is never empty)
        let irradiance = if vc.irradiance.is_empty() { vec![[0f32; 4]] } else { vc.irradiance };
        let irradiance = mk("vertex irradiance", bytemuck::cast_slice(&irradiance));
        let layout = self
            .btf
            .vertex_layout
            .as_ref()
            .ok_or_else(|| Error::Gpu("per-vertex layout missing".into()))?;
        let resources =
            [coef.as_entire_binding(), slots.as_entire_binding(), irradiance.as_entire_binding()];
        let group = crate::bind::group(&gpu.device, "per-vertex", layout, &resources);
        Ok((coef, slots, group))
    }
}
