//! Per-pass timing for `--stats`: GPU timestamp queries around each render pass when the
//! adapter supports them, otherwise CPU time around submit + wait of each pass.

use crate::frame::PassStat;
use crate::{Error, Gpu, Result};
use std::time::Instant;

/// Collects the passes of one frame.
pub struct PassTimer<'a> {
    gpu: &'a Gpu,
    query: Option<wgpu::QuerySet>,
    capacity: u32,
    names: Vec<String>,
    cpu_ms: Vec<Option<f64>>,
    pending: Vec<wgpu::CommandBuffer>,
}

impl<'a> PassTimer<'a> {
    /// A timer for at most `max_passes` GPU passes.
    pub fn new(gpu: &'a Gpu, max_passes: u32) -> Self {
        let query = gpu.timestamps.then(|| {
            gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * max_passes.max(1),
            })
        });
        PassTimer {
            gpu,
            query,
            capacity: max_passes,
            names: Vec::new(),
            cpu_ms: Vec::new(),
            pending: Vec::new(),
        }
    }

    /// How times are measured.
    pub fn method(&self) -> &'static str {
        if self.query.is_some() { "gpu-timestamps" } else { "cpu" }
    }

    /// Records CPU work as a pass.
    pub fn cpu(&mut self, name: &str, ms: f64) {
        self.names.push(name.into());
        self.cpu_ms.push(Some(ms));
    }

    /// Encodes one render pass through `f`, which must pass the given timestamp writes to
    /// its `begin_render_pass`.
    pub fn pass(
        &mut self,
        name: &str,
        f: impl FnOnce(&mut wgpu::CommandEncoder, Option<wgpu::RenderPassTimestampWrites>),
    ) -> Result<()> {
        let gpu_index = self.cpu_ms.iter().filter(|m| m.is_none()).count() as u32;
        let mut enc = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(name) });
        match &self.query {
            Some(q) if gpu_index < self.capacity => {
                f(
                    &mut enc,
                    Some(wgpu::RenderPassTimestampWrites {
                        query_set: q,
                        beginning_of_pass_write_index: Some(2 * gpu_index),
                        end_of_pass_write_index: Some(2 * gpu_index + 1),
                    }),
                );
                self.pending.push(enc.finish());
                self.cpu_ms.push(None);
            }
            _ => {
                let t = Instant::now();
                f(&mut enc, None);
                self.gpu.queue.submit([enc.finish()]);
                self.gpu.wait()?;
                self.cpu_ms.push(Some(t.elapsed().as_secs_f64() * 1e3));
            }
        }
        self.names.push(name.into());
        Ok(())
    }

    /// Submits what is pending, waits, and returns the pass times.
    pub fn finish(self) -> Result<Vec<PassStat>> {
        let n_gpu = self.cpu_ms.iter().filter(|m| m.is_none()).count() as u32;
        let mut gpu_ms = Vec::new();
        if let (Some(q), true) = (&self.query, n_gpu > 0) {
            let size = 16 * n_gpu as u64;
            let resolve = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps readback"),
                size,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            let mut enc = self.gpu.device.create_command_encoder(&Default::default());
            enc.resolve_query_set(q, 0..2 * n_gpu, &resolve, 0);
            enc.copy_buffer_to_buffer(&resolve, 0, &read, 0, size);
            let mut cmds = self.pending;
            cmds.push(enc.finish());
            self.gpu.queue.submit(cmds);
            let raw = self.gpu.read_buffer(&read)?;
            let ticks: &[u64] = bytemuck::cast_slice(&raw);
            let period_ns = self.gpu.queue.get_timestamp_period() as f64;
            gpu_ms = ticks
                .chunks_exact(2)
                .map(|t| t[1].saturating_sub(t[0]) as f64 * period_ns * 1e-6)
                .collect();
        } else if !self.pending.is_empty() {
            self.gpu.queue.submit(self.pending);
            self.gpu.wait()?;
        }
        let mut it = gpu_ms.into_iter();
        self.names
            .into_iter()
            .zip(self.cpu_ms)
            .map(|(name, cpu)| {
                let ms = match cpu {
                    Some(ms) => ms,
                    None => it.next().ok_or_else(|| Error::Gpu("missing timestamp".into()))?,
                };
                Ok(PassStat { name, ms })
            })
            .collect()
    }
}
