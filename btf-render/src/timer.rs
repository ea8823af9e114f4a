//! Per-pass timing for `--stats`, recorded into the one command encoder a frame is encoded
//! in: GPU timestamp queries around each render pass when the adapter has them (resolved at
//! the end of the same encoder, read after the caller's submit), otherwise — only when the
//! renderer owns the encoder — CPU time around a submit and wait of each pass. Work done on
//! the CPU for the frame is recorded by name with its milliseconds. No equation lives here.

use crate::frame::PassStat;
use crate::{Gpu, Result};
use std::time::Instant;

/// Most GPU passes one frame times with timestamps: the BTF pass plus the shadow passes of
/// four lights (shadow maps: six cube faces each; volumes: a prepass and two per light), the
/// environment background.
pub const MAX_TIMED_PASSES: u32 = 32;

/// How the passes of a frame are timed.
pub enum Clock<'a> {
    /// Timestamps written into `query` (two per pass).
    Timestamps(&'a wgpu::QuerySet),
    /// Each pass submitted and waited for on its own (the renderer's own encoder only).
    SubmitEach,
    /// Not timed (a caller's encoder on an adapter without timestamps).
    Untimed,
}

/// When one recorded pass was measured.
#[derive(Debug, Clone, Copy)]
enum Time {
    /// On the CPU, milliseconds.
    Cpu(f64),
    /// By timestamps `2k`, `2k + 1`.
    Gpu(u32),
    /// Not measured.
    None,
}

/// Records the passes of one frame into an encoder.
pub struct PassTimer<'a> {
    gpu: &'a Gpu,
    encoder: &'a mut wgpu::CommandEncoder,
    clock: Clock<'a>,
    names: Vec<String>,
    times: Vec<Time>,
    gpu_passes: u32,
}

impl<'a> PassTimer<'a> {
    /// A timer encoding into `encoder`, timing with `clock`.
    pub fn new(gpu: &'a Gpu, encoder: &'a mut wgpu::CommandEncoder, clock: Clock<'a>) -> Self {
        PassTimer { gpu, encoder, clock, names: Vec::new(), times: Vec::new(), gpu_passes: 0 }
    }

    /// Records CPU work as a pass.
    pub fn cpu(&mut self, name: &str, ms: f64) {
        self.names.push(name.into());
        self.times.push(Time::Cpu(ms));
    }

    /// The encoder, for work outside timed passes (copies).
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        self.encoder
    }

    /// Encodes one render pass through `f`, which must pass the given timestamp writes to
    /// its `begin_render_pass`.
    pub fn pass(
        &mut self,
        name: &str,
        f: impl FnOnce(&mut wgpu::CommandEncoder, Option<wgpu::RenderPassTimestampWrites>),
    ) -> Result<()> {
        let time = match &self.clock {
            Clock::Timestamps(query) => {
                let k = self.gpu_passes;
                assert!(k < MAX_TIMED_PASSES, "a frame has at most {MAX_TIMED_PASSES} passes");
                self.gpu_passes += 1;
                f(
                    self.encoder,
                    Some(wgpu::RenderPassTimestampWrites {
                        query_set: query,
                        beginning_of_pass_write_index: Some(2 * k),
                        end_of_pass_write_index: Some(2 * k + 1),
                    }),
                );
                Time::Gpu(k)
            }
            Clock::SubmitEach => {
                let t = Instant::now();
                f(self.encoder, None);
                let label = wgpu::CommandEncoderDescriptor { label: Some("frame") };
                let next = self.gpu.device.create_command_encoder(&label);
                let done = std::mem::replace(&mut *self.encoder, next);
                self.gpu.queue.submit([done.finish()]);
                self.gpu.wait()?;
                Time::Cpu(t.elapsed().as_secs_f64() * 1e3)
            }
            Clock::Untimed => {
                f(self.encoder, None);
                Time::None
            }
        };
        self.names.push(name.into());
        self.times.push(time);
        Ok(())
    }

    /// Records work that encodes passes of its own into the encoder (an overlay's compute
    /// and render passes): timed by a submit and wait under [`Clock::SubmitEach`], else
    /// reported untimed (the passes carry no timestamp writes of ours).
    pub fn encoded(
        &mut self,
        name: &str,
        f: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<()>,
    ) -> Result<()> {
        let time = match &self.clock {
            Clock::SubmitEach => {
                let t = Instant::now();
                f(self.encoder)?;
                let label = wgpu::CommandEncoderDescriptor { label: Some("frame") };
                let next = self.gpu.device.create_command_encoder(&label);
                let done = std::mem::replace(&mut *self.encoder, next);
                self.gpu.queue.submit([done.finish()]);
                self.gpu.wait()?;
                Time::Cpu(t.elapsed().as_secs_f64() * 1e3)
            }
            _ => {
                f(self.encoder)?;
                Time::None
            }
        };
        self.names.push(name.into());
        self.times.push(time);
        Ok(())
    }

    /// Ends the frame's record: with timestamps, resolves them into `resolve` and copies
    /// them to `read` (both at least `16 ·` [`MAX_TIMED_PASSES`] bytes) in the encoder.
    pub fn finish(self, buffers: Option<(&wgpu::Buffer, &wgpu::Buffer)>) -> PassRecord {
        if let (Clock::Timestamps(query), Some((resolve, read)), true) =
            (&self.clock, buffers, self.gpu_passes > 0)
        {
            let n = self.gpu_passes;
            self.encoder.resolve_query_set(query, 0..2 * n, resolve, 0);
            self.encoder.copy_buffer_to_buffer(resolve, 0, read, 0, 16 * n as u64);
        }
        PassRecord { names: self.names, times: self.times, gpu_passes: self.gpu_passes }
    }
}

/// The passes of an encoded frame, with the GPU times still on the device.
#[derive(Debug, Clone, Default)]
pub struct PassRecord {
    names: Vec<String>,
    times: Vec<Time>,
    gpu_passes: u32,
}

impl PassRecord {
    /// The pass times, reading the timestamps from `read` (mapped: this waits for the frame's
    /// submission to finish). Untimed passes are reported as `NaN` ms.
    pub fn stats(&self, gpu: &Gpu, read: Option<&wgpu::Buffer>) -> Result<Vec<PassStat>> {
        let mut gpu_ms = Vec::new();
        if let (Some(read), true) = (read, self.gpu_passes > 0) {
            let raw = gpu.read_buffer(read)?;
            let ticks: &[u64] = bytemuck::cast_slice(&raw[..16 * self.gpu_passes as usize]);
            let period_ns = gpu.queue.get_timestamp_period() as f64;
            gpu_ms = ticks
                .chunks_exact(2)
                .map(|t| t[1].saturating_sub(t[0]) as f64 * period_ns * 1e-6)
                .collect();
        }
        Ok(self
            .names
            .iter()
            .zip(&self.times)
            .map(|(name, time)| PassStat {
                name: name.clone(),
                ms: match *time {
                    Time::Cpu(ms) => ms,
                    Time::Gpu(k) => gpu_ms.get(k as usize).copied().unwrap_or(f64::NAN),
                    Time::None => f64::NAN,
                },
            })
            .collect())
    }
}
