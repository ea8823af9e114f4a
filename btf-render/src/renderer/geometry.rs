//! The scene's geometry as the passes draw it: the meshes merged into one (each triangle
//! with its scene material), the UV tangent frames (`btf_light::tangent`), and the corner
//! buffer sorted by material into one draw per material (the mesh drawn unindexed so each
//! corner knows its triangle's vertices for the per-vertex blending of `[S03 §4.2]`).

use crate::camera::CameraSetup;
use crate::passes::mesh::CornerVertex;
use crate::scene::Scene;
use crate::{Error, Gpu, Result};
use btf_light::mesh::Mesh;
use btf_light::tangent;
use wgpu::util::DeviceExt;

/// A run of corners of one material.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Draw {
    /// Material slot (see [`super::materials::Materials`]).
    pub material: usize,
    /// First corner.
    pub first: u32,
    /// Corners.
    pub count: u32,
}

/// The merged mesh, its tangents and materials per vertex, and its corners on the GPU.
pub(crate) struct SceneGeometry {
    /// The merged mesh.
    pub mesh: Mesh,
    /// Tangent `T` and sign per vertex.
    pub tangents: Vec<[f32; 4]>,
    /// Material slot of each vertex (`usize::MAX` for a vertex of no triangle).
    pub vertex_material: Vec<usize>,
    /// The corners, sorted by material.
    pub corners: Vec<CornerVertex>,
    /// Material slot of each sorted triangle.
    pub slot_of_triangle: Vec<usize>,
    /// [`SceneGeometry::corners`] on the GPU.
    pub corner_buffer: wgpu::Buffer,
    /// One draw per material.
    pub draws: Vec<Draw>,
}

/// Merges the scene's meshes and assigns each triangle a scene material index.
pub(crate) fn load_meshes(scene: &Scene) -> Result<(Mesh, Vec<usize>)> {
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

impl SceneGeometry {
    /// Sorts the triangles of `mesh` by material slot (`slot_of_desc[tri_desc[t]]`) and
    /// uploads their corners.
    pub fn build(
        gpu: &Gpu,
        mesh: Mesh,
        tri_desc: &[usize],
        slot_of_desc: &[usize],
    ) -> SceneGeometry {
        let tangents = tangent::compute_tangents(&mesh);
        let mut order: Vec<usize> = (0..mesh.triangles.len()).collect();
        order.sort_by_key(|&t| slot_of_desc[tri_desc[t]]);
        let mut corners = Vec::with_capacity(order.len() * 3);
        let mut draws: Vec<Draw> = Vec::new();
        let mut vertex_material = vec![usize::MAX; mesh.positions.len()];
        for &t in &order {
            let m = slot_of_desc[tri_desc[t]];
            match draws.last_mut() {
                Some(d) if d.material == m => d.count += 3,
                _ => draws.push(Draw { material: m, first: corners.len() as u32, count: 3 }),
            }
            let tri = mesh.triangles[t];
            for (corner, &v) in tri.iter().enumerate() {
                let v = v as usize;
                vertex_material[v] = m;
                corners.push(CornerVertex {
                    position: mesh.positions[v],
                    normal: mesh.normals[v],
                    tangent: tangents[v],
                    uv: mesh.uvs[v],
                    tri,
                    corner: corner as u32,
                });
            }
        }
        let slot_of_triangle = order.iter().map(|&t| slot_of_desc[tri_desc[t]]).collect();
        // A scene of [[yarns]] alone has no corners: one zeroed corner keeps the vertex
        // buffer bindable (an empty slice cannot be bound); no draw reads it.
        let padding = [<CornerVertex as bytemuck::Zeroable>::zeroed()];
        let corner_buffer = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("corners"),
            contents: bytemuck::cast_slice(if corners.is_empty() { &padding } else { &corners }),
            usage: wgpu::BufferUsages::VERTEX,
        });
        SceneGeometry {
            mesh,
            tangents,
            vertex_material,
            corners,
            slot_of_triangle,
            corner_buffer,
            draws,
        }
    }

    /// Corners of the whole mesh.
    pub fn corner_count(&self) -> u32 {
        self.corners.len() as u32
    }

    /// The camera and mesh inputs of the environment's per-vertex fill (`[S03 eq. 11]`).
    pub fn view_input<'a>(
        &'a self,
        camera: &CameraSetup,
        view_mode: btf_core::InterpMode,
        view_samplings: &'a [&'a btf_core::Sampling],
    ) -> btf_light::ViewInput<'a> {
        btf_light::ViewInput {
            eye: camera.eye,
            ortho_to_camera: camera.ortho_to_camera,
            view_mode,
            positions: &self.mesh.positions,
            normals: &self.mesh.normals,
            tangents: &self.tangents,
            material_of: &self.vertex_material,
            view_samplings,
        }
    }

    /// The mesh as the environment light reads it.
    pub fn env_mesh(&self) -> btf_light::EnvMesh<'_> {
        btf_light::EnvMesh {
            positions: &self.mesh.positions,
            normals: &self.mesh.normals,
            tangents: &self.tangents,
            triangles: &self.mesh.triangles,
        }
    }
}
