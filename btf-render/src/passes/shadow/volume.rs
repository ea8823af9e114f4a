//! Stencil shadow volumes (Crow 1977), the macroscopic shadows of `[S03 §4.3]`, robust on
//! open cloth meshes.
//!
//! Silhouette-edge volumes need closed, consistently oriented meshes; cloth has boundary
//! edges and may be non-manifold. Here every triangle casts its own closed prism: the
//! triangle oriented to face the light (front cap, pushed `ε` away from the light so that
//! the surface does not shadow itself), the same triangle extruded by `D` away from the
//! light (back cap, reversed) and three side quads. With z-fail counting a point is in
//! shadow exactly when it lies inside some prism, whatever the mesh topology. `D` exceeds
//! the scene's diameter, and the camera's far plane is moved back by `D` so back caps are
//! never clipped. Per light: a stencil pass, then a full-screen pass that writes 0 into the
//! light's mask where the stencil is not 0; the BTF pass multiplies the light by the mask
//! and by the smooth boundary of `[S03 eq. 6]` ("combined by blending"). The prisms depend
//! on the lights and the mesh only, so they are built once with the pass (and again only
//! when the lights move), not per frame.

use crate::bind::{self, uniform};
use crate::math::{self, Mat4, Vec3, v3};
use crate::passes::mesh::position_only_layout;
use crate::scene::Light;
use crate::timer::PassTimer;
use crate::{Gpu, Result};
use btf_light::mesh::Mesh;
use wgpu::util::DeviceExt;

/// WGSL of the passes.
pub const SOURCE: &str = include_str!("volume.wgsl");
/// Depth-stencil format of the prepass and the stencil counting.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;

/// Extrusion distance for a scene of bounding radius `radius`.
pub fn extrusion(radius: f32) -> f32 {
    2.5 * radius.max(1e-6)
}

/// The prisms of all triangles for one light, as homogeneous world positions (`w = 1`),
/// eight triangles per mesh triangle; zero-area triangles cast nothing.
pub fn prisms(mesh: &Mesh, light: &Light, radius: f32) -> Vec<[f32; 4]> {
    let (eps, d) = (1e-3 * radius.max(1e-6), extrusion(radius));
    let away = |p: Vec3| -> Vec3 {
        match light {
            Light::Directional { direction, .. } => -v3(*direction).normalize(),
            Light::Point { position, .. } => {
                (p - v3(*position)).try_normalize(0.0).unwrap_or(Vec3::z())
            }
            Light::Environment(_) => Vec3::zeros(), // never shadow-casting (no prisms below)
        }
    };
    if matches!(light, Light::Environment(_)) {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(mesh.triangles.len() * 24);
    for tri in &mesh.triangles {
        let [mut a, mut b, c] = tri.map(|i| v3(mesh.positions[i as usize]));
        let n = (b - a).cross(&(c - a));
        if !(n.norm() > 0.0 && n.norm().is_finite()) {
            continue;
        }
        let centroid = (a + b + c) / 3.0;
        if n.dot(&-away(centroid)) < 0.0 {
            std::mem::swap(&mut a, &mut b); // front cap faces the light
        }
        let (ea, eb, ec) = (away(a), away(b), away(c));
        let (fa, fb, fc) = (a + ea * eps, b + eb * eps, c + ec * eps);
        let (ba, bb, bc) = (a + ea * d, b + eb * d, c + ec * d);
        let mut push = |p: [Vec3; 3]| out.extend(p.iter().map(|q| [q.x, q.y, q.z, 1.0]));
        push([fa, fb, fc]);
        push([ba, bc, bb]);
        for (p, q, p2, q2) in [(fa, fb, ba, bb), (fb, fc, bb, bc), (fc, fa, bc, ba)] {
            push([p, p2, q2]);
            push([p, q2, q]);
        }
    }
    out
}

/// Depth prepass, stencil counting and mask resolve for the shadowing lights.
pub struct ShadowVolumes {
    /// `R8Unorm` mask per shadowing light (1 lit, 0 shadowed), screen-sized.
    pub masks: wgpu::Texture,
    depth: wgpu::Texture,
    camera: wgpu::Buffer,
    group: wgpu::BindGroup,
    depth_pipe: wgpu::RenderPipeline,
    volume_pipe: wgpu::RenderPipeline,
    mask_pipe: wgpu::RenderPipeline,
    /// Per shadowing light: its prisms (`vec4` positions) and their vertex count.
    prisms: Vec<(wgpu::Buffer, u32)>,
    extrusion: f32,
}

fn stencil_face(depth_fail_op: wgpu::StencilOperation) -> wgpu::StencilFaceState {
    wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op,
        pass_op: wgpu::StencilOperation::Keep,
    }
}

impl ShadowVolumes {
    /// Builds the pipelines, the prisms of `mesh` for each of `lights` and the targets for a
    /// `width × height` frame.
    pub fn new(
        gpu: &Gpu,
        lights: &[&Light],
        mesh: &Mesh,
        radius: f32,
        width: u32,
        height: u32,
    ) -> ShadowVolumes {
        use wgpu::{CompareFunction as C, StencilOperation as Op};
        let dev = &gpu.device;
        let tex = |label, format, layers, usage| {
            dev.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let att = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let masks = tex(
            "shadow masks",
            wgpu::TextureFormat::R8Unorm,
            lights.len().max(1) as u32,
            att | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let depth = tex("volume depth", FORMAT, 1, att);
        let camera = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("volume camera"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout =
            bind::layout_seen_by(dev, "volume camera", wgpu::ShaderStages::VERTEX, &[uniform()]);
        let group = bind::group(dev, "volume camera", &layout, &[camera.as_entire_binding()]);
        let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow volume"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadow_volume.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
        });
        let vec4_layout = wgpu::VertexBufferLayout {
            array_stride: 16,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x4],
        };
        let mask_target = [Some(wgpu::ColorTargetState::from(wgpu::TextureFormat::R8Unorm))];
        let pipe = |label,
                    entry,
                    buffers: &[Option<wgpu::VertexBufferLayout>],
                    ds: wgpu::DepthStencilState,
                    color: bool| {
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: Some(ds),
                multisample: Default::default(),
                fragment: color.then(|| wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_shadowed"),
                    compilation_options: Default::default(),
                    targets: &mask_target,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let ds = |write: bool, compare: C, stencil: wgpu::StencilState| wgpu::DepthStencilState {
            format: FORMAT,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil,
            bias: Default::default(),
        };
        let depth_pipe = pipe(
            "volume depth prepass",
            "vs_depth",
            &[Some(position_only_layout())],
            ds(true, C::Less, Default::default()),
            false,
        );
        let count = wgpu::StencilState {
            front: stencil_face(Op::DecrementWrap),
            back: stencil_face(Op::IncrementWrap),
            read_mask: 0xff,
            write_mask: 0xff,
        };
        let volume_pipe = pipe(
            "volume stencil",
            "vs_volume",
            &[Some(vec4_layout)],
            ds(false, C::Less, count),
            false,
        );
        let test = wgpu::StencilFaceState {
            compare: C::NotEqual,
            fail_op: Op::Keep,
            depth_fail_op: Op::Keep,
            pass_op: Op::Keep,
        };
        let resolve =
            wgpu::StencilState { front: test, back: test, read_mask: 0xff, write_mask: 0 };
        let mask_pipe =
            pipe("volume mask", "vs_fullscreen", &[], ds(false, C::Always, resolve), true);
        ShadowVolumes {
            masks,
            depth,
            camera,
            group,
            depth_pipe,
            volume_pipe,
            mask_pipe,
            prisms: lights
                .iter()
                .map(|l| {
                    let geometry = prisms(mesh, l, radius);
                    let buffer = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("shadow volume"),
                        contents: bytemuck::cast_slice(&geometry),
                        usage: wgpu::BufferUsages::VERTEX,
                    });
                    (buffer, geometry.len() as u32)
                })
                .collect(),
            extrusion: extrusion(radius),
        }
    }

    /// How far the prisms reach (the camera's far plane moves back by it).
    pub fn extrusion(&self) -> f32 {
        self.extrusion
    }

    /// Encodes the prepass, then per light the stencil counting and mask.
    pub fn encode(
        &self,
        gpu: &Gpu,
        timer: &mut PassTimer,
        corners: &wgpu::Buffer,
        n_corners: u32,
        view_proj: &Mat4,
    ) -> Result<()> {
        gpu.queue.write_buffer(&self.camera, 0, bytemuck::bytes_of(&math::to_cols(view_proj)));
        let depth_view = self.depth.create_view(&Default::default());
        let ds = |depth: wgpu::LoadOp<f32>, stencil: wgpu::LoadOp<u32>| {
            wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations { load: depth, store: wgpu::StoreOp::Store }),
                stencil_ops: Some(wgpu::Operations { load: stencil, store: wgpu::StoreOp::Store }),
            }
        };
        timer.pass("shadow volume depth prepass", |enc, ts| {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("volume depth prepass"),
                color_attachments: &[],
                depth_stencil_attachment: Some(ds(
                    wgpu::LoadOp::Clear(1.0),
                    wgpu::LoadOp::Clear(0),
                )),
                timestamp_writes: ts,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.depth_pipe);
            pass.set_bind_group(0, &self.group, &[]);
            pass.set_vertex_buffer(0, corners.slice(..));
            pass.draw(0..n_corners, 0..1);
        })?;
        for (l, (buf, vertices)) in self.prisms.iter().enumerate() {
            let mask_view = self.masks.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: l as u32,
                array_layer_count: Some(1),
                ..Default::default()
            });
            timer.pass(&format!("shadow volume L{l} stencil"), |enc, ts| {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("volume stencil"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(ds(wgpu::LoadOp::Load, wgpu::LoadOp::Clear(0))),
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.volume_pipe);
                pass.set_bind_group(0, &self.group, &[]);
                pass.set_vertex_buffer(0, buf.slice(..));
                pass.draw(0..*vertices, 0..1);
            })?;
            timer.pass(&format!("shadow volume L{l} mask"), |enc, ts| {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("volume mask"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &mask_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: Some(ds(wgpu::LoadOp::Load, wgpu::LoadOp::Load)),
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.mask_pipe);
                pass.set_bind_group(0, &self.group, &[]);
                pass.set_stencil_reference(0);
                pass.draw(0..3, 0..1);
            })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("shadow_volume.wgsl", SOURCE).unwrap();
    }

    #[test]
    fn prisms_are_closed_and_outward() {
        // A single open triangle: its prism must be closed (every edge shared by exactly two
        // prism triangles with opposite directions) and enclose positive volume.
        let mesh = Mesh::parse_obj(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1/1 1/1 2/1\n",
            "t.obj",
            None,
        )
        .unwrap();
        let light =
            Light::Directional { direction: [0.2, 0.1, 1.0], irradiance: [1.0; 3], shadows: true };
        let p = prisms(&mesh, &light, 1.0);
        assert_eq!(p.len(), 24, "the zero-area face casts nothing");
        let key = |v: [f32; 4]| v.map(|c| (c * 1e4).round() as i64);
        let mut edges = std::collections::HashMap::new();
        let mut volume = 0.0f64;
        for t in p.chunks_exact(3) {
            for k in 0..3 {
                *edges.entry((key(t[k]), key(t[(k + 1) % 3]))).or_insert(0) += 1;
            }
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| Vec3::new(v[0], v[1], v[2]));
            volume += a.dot(&b.cross(&c)) as f64 / 6.0;
        }
        for ((a, b), n) in &edges {
            assert_eq!(*n, 1);
            assert_eq!(edges.get(&(*b, *a)), Some(&1), "edge without its twin");
        }
        assert!(volume > 0.0, "outward orientation: signed volume {volume}");
    }
}
