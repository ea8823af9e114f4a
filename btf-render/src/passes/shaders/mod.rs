//! WGSL shared by several passes: `interp.wgsl`, the GPU side of the interpolation weights
//! of `[S03 eq. 3, 5]` (the algorithm of `btf_core::interp` in WGSL), prepended to the BTF,
//! thin and baseline shaders. This module checks on the device that both give the same
//! weights, via the `interp_probe.wgsl` compute shader (was `interp.rs`).

#[cfg(test)]
/// The probe shader (interpolation functions + compute entry point).
pub const PROBE_SOURCE: &str =
    concat!(include_str!("interp.wgsl"), include_str!("interp_probe.wgsl"));

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Gpu;
    use crate::bind;
    use crate::material::SamplingsRaw;
    use btf_core::{Direction, InterpMode, Sampling, Weights};
    use wgpu::util::DeviceExt;

    #[test]
    fn probe_validates() {
        crate::gpu::validate_wgsl("interp_probe.wgsl", PROBE_SOURCE).unwrap();
    }

    fn run_probe(gpu: &Gpu, s: &Sampling, dirs: &[[f32; 4]]) -> Vec<[f32; 4]> {
        let dev = &gpu.device;
        let uni = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::bytes_of(&SamplingsRaw::of_samplings(s, s)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let din = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(dirs),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let size = (dirs.len() * 8 * 16) as u64;
        let out = dev.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read = dev.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("interp_probe"),
            source: wgpu::ShaderSource::Wgsl(PROBE_SOURCE.into()),
        });
        let pipe = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: None,
            layout: None,
            module: &module,
            entry_point: Some("probe"),
            compilation_options: Default::default(),
            cache: None,
        });
        let resources = [uni.as_entire_binding(), din.as_entire_binding(), out.as_entire_binding()];
        let bg = bind::group(dev, "interp probe", &pipe.get_bind_group_layout(0), &resources);
        let mut enc = dev.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipe);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups((dirs.len() as u32).div_ceil(64), 1, 1);
        }
        enc.copy_buffer_to_buffer(&out, 0, &read, 0, size);
        gpu.queue.submit([enc.finish()]);
        bytemuck::cast_slice(&gpu.read_buffer(&read).unwrap()).to_vec()
    }

    fn l1(gpu_idx: [f32; 4], gpu_w: [f32; 4], cpu: &Weights, n: usize) -> f64 {
        let idx: [u32; 4] = bytemuck::cast(gpu_idx);
        let mut dense = vec![0f64; n];
        for k in 0..4 {
            if gpu_w[k] > 0.0 {
                dense[idx[k] as usize] += gpu_w[k] as f64;
            }
        }
        (0..n).map(|i| (dense[i] - cpu.weight_of(i)).abs()).sum()
    }

    #[test]
    fn wgsl_weights_match_cpu_weights() {
        let Some(gpu) = Gpu::for_tests("wgsl_weights_match_cpu_weights") else { return };
        // Hard cases first: pole, φ = 0 and 360, ring boundaries, beyond the last ring,
        // the horizon and below; then a dense sweep.
        let mut angles: Vec<(f64, f64)> = vec![
            (0.0, 0.0),
            (0.0, 123.0),
            (1e-4, 359.9999),
            (15.0, 0.0),
            (30.0, 360.0),
            (80.0, 10.0),
            (90.0, 5.0),
            (95.0, 5.0),
            (89.9, 355.0),
        ];
        for k in 0..1500 {
            angles.push(((k as f64 * 0.0613) % 92.0, (k as f64 * 7.31) % 360.0));
        }
        for name in btf_core::sampling::SAMPLING_NAMES {
            let s = Sampling::by_name(name).unwrap();
            let dirs: Vec<[f32; 4]> = angles
                .iter()
                .map(|&(t, p)| {
                    let v = Direction::new(t, p).to_vector();
                    [v[0] as f32, v[1] as f32, v[2] as f32, 0.0]
                })
                .collect();
            let out = run_probe(&gpu, &s, &dirs);
            let mut worst = 0f64;
            for (d, &(t, p)) in angles.iter().enumerate() {
                // The CPU sees the same f32 vector the GPU sees.
                let v = dirs[d];
                let dir = Direction::from_vector([v[0] as f64, v[1] as f64, v[2] as f64]).unwrap();
                let cpu = [
                    s.view_weights(dir, InterpMode::Four),
                    s.view_weights(dir, InterpMode::Nearest),
                    s.light_weights(dir, InterpMode::Four),
                    s.light_weights(dir, InterpMode::Nearest),
                ];
                for (m, c) in cpu.iter().enumerate() {
                    let e = l1(out[d * 8 + 2 * m], out[d * 8 + 2 * m + 1], c, s.len());
                    // Nearest may legitimately differ exactly at a tie; four must agree to f32.
                    let tol = if m % 2 == 0 { 2e-3 } else { 1e-6 };
                    let at_tie = m % 2 == 1 && e > tol;
                    if !at_tie {
                        assert!(e <= tol, "{name} θ={t} φ={p} mode {m}: L1 {e}, cpu {c:?}");
                    }
                    if m % 2 == 0 {
                        worst = worst.max(e);
                    }
                }
            }
            eprintln!("{name}: worst L1 between WGSL and CPU four-nearest weights {worst:.2e}");
        }
    }
}
