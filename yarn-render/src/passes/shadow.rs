//! `yarn_tube_shadow` (render, depth only): the shadow maps of the yarns drawn as thick
//! tubes of the yarn radius [W19 §4.1], light-facing strips pulled from the control points
//! like the fibers. The fiber shader reads them at the yarn centre moved towards the light
//! by the tube radius, so a yarn is shadowed by other yarns only; its own fibers' shadows
//! are the self-shadow volume's (`crate::effects`). The tube radius is the yarn radius
//! without flyaways (DESIGN §2.3 item 14).
//!
//! A directional light (or an SRBF lobe of an environment) gets one orthographic map over
//! the yarns' bounding sphere ([`light_views`]). A point light ([`point_views`]) gets one
//! perspective map from the light when the sphere subtends at most 120° there, and six
//! 92° cube faces otherwise (a light inside or near the yarns); the strips face the light
//! from each vertex. Perspective depth is not linear, so its bias is a distance along the
//! light ray (the same metres as the orthographic maps' depth bias), not a depth offset.

use crate::gpu_data::YarnBuffers;
use crate::passes::draw::DEPTH;
use crate::view::{FiberCamera, FiberLight, ViewSetup, to_cols};
use crate::{Error, Result};
use btf_render::Gpu;
use wgpu::util::DeviceExt;

const WGSL: &str = include_str!("../shaders/yarn_tube_shadow.wgsl");

/// The pass's WGSL (generator in front).
pub fn source() -> String {
    crate::with_generator(WGSL)
}

/// The most shadowed directional lights per frame.
pub const MAX_SHADOW_MAPS: usize = 4;

/// The uniform of one shadow pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowPassRaw {
    /// Origin-relative world → light clip.
    pub view_proj: [[f32; 4]; 4],
    /// Unit direction towards the light (w = 0), or the point light's origin-relative
    /// position (w = 1).
    pub to_light: [f32; 4],
    /// Subdivisions per segment.
    pub n: [u32; 4],
}

/// The most maps a fiber frame reads: six per shadowed light (cube faces) and one per SRBF.
pub const MAX_FIBER_MAPS: usize = 6 * MAX_SHADOW_MAPS + crate::strips::MAX_SRBFS;

/// The light index of SRBF `j` in the maps' light lists.
pub fn srbf_light(j: usize) -> u32 {
    (crate::view::MAX_LIGHTS + j) as u32
}

/// The shadow maps as the fiber and strip shaders read them (uniform, `ShadowViews` of
/// `fiber_shading.wgsl`): per map its light (light `i`, or SRBF `j` as [`srbf_light`]), its
/// PCSS scale and its biases; the shaders take the first map of the light that sees the
/// point.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowViewsRaw {
    /// World → light clip per map.
    pub view_proj: [[[f32; 4]; 4]; MAX_FIBER_MAPS],
    /// Maps in use.
    pub n: [u32; 4],
    /// The light each map belongs to.
    pub light: [[u32; 4]; MAX_FIBER_MAPS / 4],
    /// 1/size, unused ×3.
    pub texel: [f32; 4],
    /// Per map: PCSS penumbra texels per unit of light-clip depth gap (0: hard).
    pub pcss: [[f32; 4]; MAX_FIBER_MAPS / 4],
    /// Per map: depth bias (clip depth), bias along the light ray (metres), the fiber
    /// shader's PCF tap spacing (texels), unused.
    pub bias: [[f32; 4]; MAX_FIBER_MAPS],
}

impl ShadowViewsRaw {
    /// No maps, for `size²`-texel maps.
    pub fn empty(size: u32) -> Self {
        let mut v: Self = bytemuck::Zeroable::zeroed();
        v.texel = [1.0 / size as f32, 0.0, 0.0, 0.0];
        v
    }
}

/// One shadow map of a frame.
#[derive(Debug, Clone, Copy)]
pub struct MapView {
    /// The pass uniform.
    pub pass: ShadowPassRaw,
    /// The light (or [`srbf_light`]) it belongs to.
    pub light: u32,
    /// Light-clip depth per metre along the light at the scene centre (PCSS).
    pub depth_per_metre: f64,
    /// Depth bias (clip depth) and bias along the light ray (metres).
    pub bias: [f32; 2],
    /// PCSS penumbra texels per unit of light-clip depth gap (0: a hard map; the strips).
    pub pcss: f32,
    /// Spacing of the fiber shader's 3 × 3 PCF taps, texels (1: a delta light's).
    pub spread: f32,
}

/// The PCSS angular radius of an SRBF lobe of sharpness `λ`: `atan(1/√λ)` (one standard
/// deviation of the lobe, DESIGN §3.3 item 14), at most 44°, in degrees.
pub fn srbf_angle_deg(lambda: f64) -> f64 {
    (1.0 / lambda.sqrt()).atan().to_degrees().min(44.0)
}

/// The orthographic maps' depth bias (clip depth over the sphere's 2.1 radii).
const ORTHO_BIAS: f32 = 2e-3;

/// The compiled pass.
pub struct ShadowPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl ShadowPass {
    /// Compiles the pass for `data`'s group-0 layout.
    pub fn new(gpu: &Gpu, data: &YarnBuffers) -> Result<Self> {
        let dev = &gpu.device;
        let layout =
            btf_render::gpu::uniform_layout(dev, "yarn_tube_shadow", wgpu::ShaderStages::VERTEX);
        let src = source();
        let pipeline = gpu
            .scoped("yarn_tube_shadow pipeline", || {
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("yarn_tube_shadow.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
                let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("yarn_tube_shadow"),
                    bind_group_layouts: &[Some(&data.layout), Some(&layout)],
                    immediate_size: 0,
                });
                dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("yarn_tube_shadow"),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_shadow"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleStrip,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: None,
                    multiview_mask: None,
                    cache: None,
                })
            })
            .map_err(|e| Error::Gpu(e.to_string()))?;
        Ok(ShadowPass { pipeline, layout })
    }

    /// Records one map per entry of `passes` into the layers of `maps` from `first_layer`
    /// on (a depth 2-D array with that many layers); with no passes, layer `first_layer`
    /// is cleared (a bound map must have been written).
    pub fn encode(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        data: &YarnBuffers,
        maps: &wgpu::Texture,
        (first_layer, passes): (u32, &[ShadowPassRaw]),
    ) {
        let dev = &gpu.device;
        let begin = |enc: &mut wgpu::CommandEncoder, layer: u32| {
            let view = maps.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            });
            enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("yarn_tube_shadow"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            })
            .forget_lifetime()
        };
        if passes.is_empty() {
            drop(begin(enc, first_layer));
            return;
        }
        for (layer, raw) in passes.iter().enumerate() {
            let ubuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("yarn_tube_shadow"),
                contents: bytemuck::bytes_of(raw),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bg = dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("yarn_tube_shadow"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: ubuf.as_entire_binding() }],
            });
            let mut pass = begin(enc, first_layer + layer as u32);
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &data.bind_group, &[]);
            pass.set_bind_group(1, &bg, &[]);
            pass.draw(0..2 * (raw.n[0] + 1), 0..data.segment_count);
        }
    }
}

/// One orthographic light view per unit direction of `dirs` (towards the light) for a
/// scene within `radius` of `centre` (origin-relative), side `2·radius`, `size²` texels:
/// the pass uniform and the light-clip depth per metre along the light (PCSS turns depth
/// gaps into metres).
pub fn light_views(
    dirs: &[[f64; 3]],
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    size: u32,
) -> Result<Vec<(ShadowPassRaw, f64)>> {
    let mut out = Vec::new();
    for &dir in dirs {
        let n = (dir.iter().map(|x| x * x).sum::<f64>()).sqrt();
        if !(n > 0.0 && n.is_finite()) {
            return Err(Error::Invalid(format!("shadow view: light direction {dir:?}")));
        }
        let d = dir.map(|x| x / n);
        let r = radius;
        let c = [0, 1, 2].map(|a| centre[a] + origin[a]);
        let eye = [0, 1, 2].map(|a| c[a] + d[a] * 2.0 * r);
        let up = if d[2].abs() < 0.9 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
        let cam = FiberCamera::orthographic(eye, c, up, 2.0 * r);
        let setup = ViewSetup::new(&cam, origin, centre, r, (size, size))?;
        let m = &setup.view_proj;
        let depth_per_metre = (m[(2, 0)] * d[0] + m[(2, 1)] * d[1] + m[(2, 2)] * d[2]).abs();
        out.push((
            ShadowPassRaw {
                view_proj: to_cols(m),
                to_light: [d[0] as f32, d[1] as f32, d[2] as f32, 0.0],
                n: [8, 0, 0, 0],
            },
            depth_per_metre,
        ));
    }
    Ok(out)
}

/// The perspective map (or cube faces) of a point light at `position` (origin-relative)
/// for a scene within `radius` of `centre` (module docs), `size²` texels each.
pub fn point_views(
    position: [f64; 3],
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    size: u32,
) -> Result<Vec<ShadowPassRaw>> {
    let to_light = [position[0] as f32, position[1] as f32, position[2] as f32, 1.0];
    point_cameras(position, origin, centre, radius)?
        .iter()
        .map(|cam| {
            let setup = ViewSetup::new(cam, origin, centre, radius, (size, size))?;
            Ok(ShadowPassRaw { view_proj: to_cols(&setup.view_proj), to_light, n: [8, 0, 0, 0] })
        })
        .collect()
}

/// The cameras of [`point_views`]: one perspective camera from the light, or the cube
/// faces that see the sphere.
pub fn point_cameras(
    position: [f64; 3],
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
) -> Result<Vec<FiberCamera>> {
    if !position.iter().all(|x| x.is_finite()) {
        return Err(Error::Invalid(format!("shadow view: point light at {position:?}")));
    }
    let r = radius.max(1e-9) * 1.05;
    let d: [f64; 3] = [0, 1, 2].map(|a| centre[a] - position[a]);
    let dist = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    let world = |p: [f64; 3]| [0, 1, 2].map(|a| p[a] + origin[a]);
    // One map while the sphere subtends at most 120° (half-angle 60°).
    if r < dist * 60f64.to_radians().sin() {
        let half = (r / dist).asin().to_degrees() * 1.02;
        let up = if (d[2] / dist).abs() < 0.9 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
        return Ok(vec![FiberCamera::perspective(world(position), world(centre), up, 2.0 * half)]);
    }
    // Cube faces, 92° so that neighbours overlap; faces that miss the sphere are left out.
    let mut out = Vec::new();
    for (axis, up) in [
        ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
        ([0.0, 0.0, -1.0], [1.0, 0.0, 0.0]),
    ] {
        let along: f64 = (0..3).map(|a| d[a] * axis[a]).sum();
        if along + r <= 0.0 {
            continue;
        }
        let target = [0, 1, 2].map(|a| position[a] + axis[a]);
        out.push(FiberCamera::perspective(world(position), world(target), up, 92.0));
    }
    Ok(out)
}

/// The shadow maps of the first [`MAX_SHADOW_MAPS`] directional and point lights of
/// `lights` and of every direction of `srbfs` (orthographic, [`srbf_light`]) for a scene
/// within `radius` of `centre` (origin-relative). PCSS on the orthographic maps with the
/// angular radius `angles.0` (degrees) for directional lights and `angles.1` for the
/// SRBFs (0: hard); a point light's perspective maps are hard.
pub fn frame_views(
    lights: &[FiberLight],
    srbfs: &[[f64; 3]],
    angles: (f64, f64),
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    size: u32,
) -> Result<Vec<MapView>> {
    let world_bias = (ORTHO_BIAS as f64 * 1.05 * radius.max(1e-9)) as f32;
    let metres_per_texel = 2.0 * radius / size as f64;
    // Penumbra (texels) = depth gap / (depth per metre) · tan(angle) / (metres per texel).
    let pcss = |angle: f64, dpm: f64| {
        let tan = angle.to_radians().tan();
        if tan > 0.0 { (tan / (dpm * metres_per_texel)) as f32 } else { 0.0 }
    };
    let mut out = Vec::new();
    for (i, l) in lights.iter().take(MAX_SHADOW_MAPS).enumerate() {
        match *l {
            FiberLight::Directional { to_light, .. } => {
                let (pass, dpm) = light_views(&[to_light], origin, centre, radius, size)?[0];
                out.push(MapView {
                    pass,
                    light: i as u32,
                    depth_per_metre: dpm,
                    bias: [ORTHO_BIAS, 0.0],
                    pcss: pcss(angles.0, dpm),
                    spread: 1.0,
                });
            }
            FiberLight::Point { position, .. } => {
                let p = [0, 1, 2].map(|a| position[a] - origin[a]);
                for pass in point_views(p, origin, centre, radius, size)? {
                    out.push(MapView {
                        pass,
                        light: i as u32,
                        depth_per_metre: f64::NAN,
                        bias: [0.0, world_bias],
                        pcss: 0.0,
                        spread: 1.0,
                    });
                }
            }
        }
    }
    for (j, (pass, dpm)) in
        light_views(srbfs, origin, centre, radius, size)?.into_iter().enumerate()
    {
        out.push(MapView {
            pass,
            light: srbf_light(j),
            depth_per_metre: dpm,
            bias: [ORTHO_BIAS, 0.0],
            pcss: pcss(angles.1, dpm),
            spread: 1.0,
        });
    }
    if out.len() > MAX_FIBER_MAPS {
        return Err(Error::Limit(format!(
            "{} shadow maps in one frame (at most {MAX_FIBER_MAPS})",
            out.len()
        )));
    }
    Ok(out)
}

/// The uniform the fiber shader reads `views` with (`size²`-texel maps).
pub fn views_raw(views: &[MapView], size: u32) -> ShadowViewsRaw {
    let mut raw = ShadowViewsRaw::empty(size);
    for (m, v) in views.iter().enumerate() {
        raw.view_proj[m] = v.pass.view_proj;
        raw.light[m / 4][m % 4] = v.light;
        raw.bias[m] = [v.bias[0], v.bias[1], v.spread, 0.0];
        raw.pcss[m / 4][m % 4] = v.pcss;
    }
    raw.n[0] = views.len() as u32;
    raw
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix4, Vector4};

    /// Where `p` (origin-relative) lands in `pass`'s map: `(u, v, depth)` if in front.
    fn project(pass: &ShadowPassRaw, p: [f64; 3]) -> Option<[f64; 3]> {
        let m = Matrix4::from_fn(|r, c| pass.view_proj[c][r] as f64);
        let c = m * Vector4::new(p[0], p[1], p[2], 1.0);
        (c.w > 0.0).then(|| [0.5 * c.x / c.w + 0.5, 0.5 - 0.5 * c.y / c.w, c.z / c.w])
    }

    fn inside(x: [f64; 3]) -> bool {
        x.iter().all(|v| (0.0..=1.0).contains(v))
    }

    /// Points of the sphere of `radius` about `centre`: a Fibonacci set at four radii.
    fn sphere_points(centre: [f64; 3], radius: f64) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        for k in 1..=4 {
            for d in yarn_precompute::srbf::fibonacci_sphere(200) {
                let r = radius * k as f64 / 4.0;
                out.push([0, 1, 2].map(|a| centre[a] + d[a] * r));
            }
        }
        out
    }

    #[test]
    fn a_far_point_light_has_one_map_that_sees_the_whole_sphere() {
        let (centre, radius) = ([0.01, -0.02, 0.003], 0.01);
        let light = [0.05, 0.02, 0.04];
        let views = point_views(light, [0.0; 3], centre, radius, 256).unwrap();
        assert_eq!(views.len(), 1);
        for p in sphere_points(centre, radius) {
            let x = project(&views[0], p).expect("in front of the light");
            assert!(inside(x), "{p:?} → {x:?}");
        }
    }

    #[test]
    fn a_point_light_among_the_yarns_gets_cube_faces_that_see_every_point() {
        let (centre, radius) = ([0.0; 3], 0.01);
        for light in [[0.0, 0.0, 0.002], [0.004, -0.003, 0.0], [0.0, 0.0, 0.0105]] {
            let views = point_views(light, [0.0; 3], centre, radius, 256).unwrap();
            assert!(views.len() >= 5, "{} faces for a light at {light:?}", views.len());
            for p in sphere_points(centre, radius) {
                let d = (0..3).map(|a| (p[a] - light[a]).powi(2)).sum::<f64>().sqrt();
                if d < 1e-6 {
                    continue;
                }
                let seen = views.iter().filter_map(|v| project(v, p)).any(inside);
                assert!(seen, "light {light:?}: no face sees {p:?}");
            }
        }
    }

    #[test]
    fn frame_views_list_each_lights_maps_then_the_srbfs() {
        let lights = [
            FiberLight::Point { position: [0.0, 0.0, 0.002], intensity: [1.0; 3] },
            FiberLight::Directional { to_light: [0.0, 0.0, 1.0], irradiance: [1.0; 3] },
        ];
        let srbfs = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let v = frame_views(&lights, &srbfs, (0.0, 10.0), [0.0; 3], [0.0; 3], 0.01, 64).unwrap();
        let lights_of: Vec<u32> = v.iter().map(|m| m.light).collect();
        let faces = lights_of.iter().filter(|&&l| l == 0).count();
        assert_eq!(faces, 6);
        assert_eq!(&lights_of[faces..], &[1, srbf_light(0), srbf_light(1)]);
        // Perspective maps are biased along the ray; orthographic ones in depth.
        assert!(v[0].bias[0] == 0.0 && v[0].bias[1] > 0.0);
        assert!(v[faces].bias[0] > 0.0 && v[faces].bias[1] == 0.0);
        // PCSS only where an angle is given: the SRBFs here, not the hard maps.
        assert!(v[..=faces].iter().all(|m| m.pcss == 0.0));
        assert!(v[faces + 1..].iter().all(|m| m.pcss > 0.0));
        let raw = views_raw(&v, 64);
        assert_eq!(raw.n[0] as usize, v.len());
        assert_eq!(raw.light[1][3], srbf_light(0));
    }
}
