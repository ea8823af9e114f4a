//! The knot solver of [H25 §5.2] as a WGSL compute pass (`shaders/knot_solve.wgsl`): the
//! per-face guarded Gauss–Newton of `yarn::knit::knot` (DESIGN §3.3 items 3–4, signed
//! weighted residuals of [H25 eq. 5–6], knot points of [H25 eq. 1–2]) in f32, one
//! invocation per knot face — written to measure whether a GPU solve pays (the issue's "a
//! WGSL version only if it measures faster").
//!
//! Per frame the CPU prepares what the CPU solve prepares too ([`KnotModel::prepare`]:
//! face frames, initial `Θ`, every CP), the pass iterates every face with its neighbours
//! fixed, and the CPU re-evaluates the knot points from the read-back `Θ`
//! ([`KnotModel::frame_from_theta`]). The stencils (points and residuals per face) are
//! uploaded once per model. Positions are sent relative to the mesh's first corner, so
//! f32 keeps ~1e-7 of the garment's extent.
//!
//! **Measured, and why it is not the default** (BENCHMARKS.md "Knit that deforms", `cargo
//! bench -p yarn-render --bench knot_gpu`): on this machine's only adapter (lavapipe, 8 f32
//! lanes on the same two CPU cores) a frame takes 2.0–3.8× the CPU solve's time in the same
//! run (1 024 to 99 856 faces; at 10⁵ faces the pass and read-back alone, 713 ms, exceed
//! the whole CPU solve, 426 ms), with knot points within 2.1e-4 r of the CPU's. So the
//! commands keep the CPU solve (f64, serial = parallel bit for bit); the pass stays as the
//! measured alternative for an adapter that is a GPU, tested against the CPU solve.

use crate::{Error, Result};
use btf_render::Gpu;
use wgpu::util::DeviceExt;
use yarn::knit::knot::{FlatStencils, Prepared, SolveStats, Theta};
use yarn::knit::{KnotFrame, KnotModel, KnotParams, StitchMesh};

const WGSL: &str = include_str!("shaders/knot_solve.wgsl");

/// Locals per face the shader holds (its `MAXL`).
const MAX_LOCALS: u32 = 48;

/// The pass's WGSL.
pub fn source() -> String {
    WGSL.to_string()
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsRaw {
    l0: [f32; 4],
    l1: [f32; 4],
    r: f32,
    h: f32,
    sqrt_w_length: f32,
    sqrt_w_angle: f32,
    iterations: u32,
    faces: u32,
    converged: f32,
    row_stride: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FaceRaw {
    sigma: f32,
    b_own: [f32; 2],
    local_start: u32,
    local_count: u32,
    res_start: u32,
    res_count: u32,
    _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LocalRaw {
    global: u32,
    flags: u32,
    wrap: i32,
    course_wrap: i32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ResRaw {
    a: u32,
    b: u32,
    c: u32,
    rest: f32,
}

/// Where the time of one GPU solve went (seconds).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KnotGpuTiming {
    /// Frames, initial `Θ` and CPs on the CPU ([`KnotModel::prepare`]).
    pub prepare: f64,
    /// Packing and uploading the frame's data.
    pub upload: f64,
    /// The pass and the read-back of `Θ`, waited for.
    pub gpu: f64,
    /// Knot points from the read-back `Θ` ([`KnotModel::frame_from_theta`]).
    pub finish: f64,
}

/// The compiled pass with one model's stencils on the device.
pub struct KnotGpuSolver {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    faces: wgpu::Buffer,
    locals: wgpu::Buffer,
    residuals: wgpu::Buffer,
    face_count: u32,
    cp_count: usize,
}

fn storage(gpu: &Gpu, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    // An empty binding is invalid: at least 16 bytes.
    let pad = [0u8; 16];
    gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: if bytes.is_empty() { &pad } else { bytes },
        usage: wgpu::BufferUsages::STORAGE,
    })
}

impl KnotGpuSolver {
    /// Compiles the pass and uploads `model`'s stencils. A face with more stencil points
    /// than the shader holds is refused, naming it.
    pub fn new(gpu: &Gpu, model: &KnotModel) -> Result<Self> {
        let flat: FlatStencils = model.flat_stencils();
        let mut faces = Vec::with_capacity(flat.faces.len());
        for (f, fc) in flat.faces.iter().enumerate() {
            if fc.locals.1 > MAX_LOCALS {
                let (c, w) = model.face_cell(f);
                return Err(Error::Invalid(format!(
                    "knot solve on the GPU: knot face {f} (course {c}, wale {w}) has {} stencil \
                     points, more than the shader's {MAX_LOCALS}",
                    fc.locals.1
                )));
            }
            faces.push(FaceRaw {
                sigma: fc.sigma as f32,
                b_own: fc.b_own.map(|x| x as f32),
                local_start: fc.locals.0,
                local_count: fc.locals.1,
                res_start: fc.residuals.0,
                res_count: fc.residuals.1,
                _pad: 0,
            });
        }
        let locals: Vec<LocalRaw> = flat
            .locals
            .iter()
            .map(|l| {
                let (flags, course_wrap) = match l.owned {
                    Some(k) => (
                        1 | (k.knot as u32 & 1) << 1
                            | (k.role as u32 & 3) << 2
                            | (k.own as u32) << 4,
                        k.course_wrap as i32,
                    ),
                    None => (0, 0),
                };
                LocalRaw { global: l.global, flags, wrap: l.wrap, course_wrap }
            })
            .collect();
        let residuals: Vec<ResRaw> = flat
            .residuals
            .iter()
            .map(|r| ResRaw {
                a: r.a as u32,
                b: r.b as u32,
                c: r.c.map_or(u32::MAX, |c| c as u32),
                rest: r.rest as f32,
            })
            .collect();
        let dev = &gpu.device;
        let buf = |binding, read_only: Option<bool>| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: match read_only {
                    None => wgpu::BufferBindingType::Uniform,
                    Some(read_only) => wgpu::BufferBindingType::Storage { read_only },
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("knot_solve"),
            entries: &[
                buf(0, None),
                buf(1, Some(true)),
                buf(2, Some(true)),
                buf(3, Some(true)),
                buf(4, Some(true)),
                buf(5, Some(true)),
                buf(6, Some(true)),
                buf(7, Some(false)),
                buf(8, Some(false)),
            ],
        });
        let pipeline = gpu
            .scoped("knot_solve pipeline", || {
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("knot_solve.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(WGSL.into()),
                });
                let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("knot_solve"),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                });
                dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("knot_solve"),
                    layout: Some(&pl),
                    module: &module,
                    entry_point: Some("solve"),
                    compilation_options: Default::default(),
                    cache: None,
                })
            })
            .map_err(|e| Error::Gpu(e.to_string()))?;
        Ok(KnotGpuSolver {
            pipeline,
            layout,
            faces: storage(gpu, "knot faces", bytemuck::cast_slice(&faces)),
            locals: storage(gpu, "knot locals", bytemuck::cast_slice(&locals)),
            residuals: storage(gpu, "knot residuals", bytemuck::cast_slice(&residuals)),
            face_count: faces.len() as u32,
            cp_count: model.cp_count(),
        })
    }

    /// One frame: [`KnotModel::prepare`] on the CPU, `p.iterations` guarded Gauss–Newton
    /// steps per face on the GPU, knot points from the read-back parameters. The frame's
    /// statistics count faces, guard triggers and rejected steps (no energies: the pass
    /// does not return them).
    pub fn solve(
        &self,
        gpu: &Gpu,
        model: &KnotModel,
        mesh: &StitchMesh,
        p: &KnotParams,
    ) -> Result<(KnotFrame, KnotGpuTiming)> {
        if model.cp_count() != self.cp_count || model.knot_faces() != self.face_count as usize {
            return Err(Error::Invalid(format!(
                "knot solve on the GPU: a model of {} CPs and {} knot faces, the pass was built \
                 for {} and {}",
                model.cp_count(),
                model.knot_faces(),
                self.cp_count,
                self.face_count
            )));
        }
        let mut timing = KnotGpuTiming::default();
        let t = std::time::Instant::now();
        let prep: Prepared = model.prepare(mesh, p)?;
        timing.prepare = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let origin = mesh.corners.first().copied().unwrap_or([0.0; 3]);
        let rel = |q: [f64; 3]| {
            [(q[0] - origin[0]) as f32, (q[1] - origin[1]) as f32, (q[2] - origin[2]) as f32]
        };
        let dir = |q: [f64; 3]| [q[0] as f32, q[1] as f32, q[2] as f32];
        let v4 = |q: [f32; 3], w: f32| [q[0], q[1], q[2], w];
        let frames: Vec<[[f32; 4]; 8]> = prep
            .frames
            .iter()
            .map(|f| {
                [
                    v4(rel(f.xk[0]), f.o as f32),
                    v4(rel(f.xk[1]), 0.0),
                    v4(dir(f.e1[0]), 0.0),
                    v4(dir(f.e1[1]), 0.0),
                    v4(dir(f.e2[0]), 0.0),
                    v4(dir(f.e2[1]), 0.0),
                    v4(dir(f.n[0]), 0.0),
                    v4(dir(f.n[1]), 0.0),
                ]
            })
            .collect();
        let points: Vec<[f32; 4]> = prep.points.iter().map(|&q| v4(rel(q), 0.0)).collect();
        let theta: Vec<[f32; 4]> = prep.theta.iter().map(|t| t.map(|x| x as f32)).collect();
        let lat = prep.lattice.map_or([[0.0; 4]; 2], |l| [v4(dir(l[0]), 0.0), v4(dir(l[1]), 0.0)]);
        let (gx, gy) = crate::passes::dispatch_size(self.face_count as u64, 64);
        let params = ParamsRaw {
            l0: lat[0],
            l1: lat[1],
            r: model.radius() as f32,
            h: model.skeleton().depth as f32,
            sqrt_w_length: p.w_length.sqrt() as f32,
            sqrt_w_angle: p.w_angle.sqrt() as f32,
            iterations: p.iterations as u32,
            faces: self.face_count,
            // f32 residuals of a face at rest: ~1e-5 (relative lengths × √w_length).
            converged: 1e-8,
            row_stride: gx * 64,
        };
        let dev = &gpu.device;
        let uniform = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("knot params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let frames = storage(gpu, "knot frames", bytemuck::cast_slice(&frames));
        let points = storage(gpu, "knot points", bytemuck::cast_slice(&points));
        let theta_in = storage(gpu, "knot theta in", bytemuck::cast_slice(&theta));
        let out_bytes = (self.face_count as u64 * 16).max(16);
        let count_bytes = (self.face_count as u64 * 8).max(16);
        let out = |label, size| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let read = |label, size| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (theta_out, counts) =
            (out("knot theta out", out_bytes), out("knot counts", count_bytes));
        let (theta_read, counts_read) =
            (read("knot theta read", out_bytes), read("knot counts read", count_bytes));
        let entries: Vec<wgpu::BindGroupEntry> = [
            &uniform,
            &self.faces,
            &self.locals,
            &self.residuals,
            &frames,
            &points,
            &theta_in,
            &theta_out,
            &counts,
        ]
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
        .collect();
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("knot_solve"),
            layout: &self.layout,
            entries: &entries,
        });
        timing.upload = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        gpu.scoped("knot_solve dispatch", || {
            let mut enc = dev.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("knot_solve"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            enc.copy_buffer_to_buffer(&theta_out, 0, &theta_read, 0, out_bytes);
            enc.copy_buffer_to_buffer(&counts, 0, &counts_read, 0, count_bytes);
            gpu.queue.submit([enc.finish()]);
        })
        .map_err(|e| Error::Gpu(e.to_string()))?;
        let theta_bytes = gpu.read_buffer(&theta_read)?;
        let count_bytes = gpu.read_buffer(&counts_read)?;
        timing.gpu = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let n = self.face_count as usize;
        let th: &[[f32; 4]] = bytemuck::cast_slice(&theta_bytes[..16 * n]);
        let cn: &[[u32; 2]] = bytemuck::cast_slice(&count_bytes[..8 * n]);
        let theta: Vec<Theta> = th.iter().map(|t| t.map(|x| x as f64)).collect();
        let stats = SolveStats {
            faces: n,
            guard_triggers: cn.iter().map(|c| c[0] as usize).sum(),
            rejected_steps: cn.iter().map(|c| c[1] as usize).sum(),
            ..SolveStats::default()
        };
        let frame = model
            .frame_from_theta(prep, theta, stats)
            .map_err(|e| Error::Invalid(format!("knot solve on the GPU: {e}")))?;
        timing.finish = t.elapsed().as_secs_f64();
        Ok((frame, timing))
    }
}
