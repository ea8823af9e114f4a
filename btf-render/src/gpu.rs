//! Headless GPU context: instance, adapter and device without a window (Mesa's lavapipe on
//! machines without a GPU), error scopes turned into [`Error::Gpu`], and texture read-back.
//!
//! No equation of the paper lives here; this is the plumbing every pass shares.

use crate::{Error, Result};
use std::sync::mpsc;

/// A device and its queue, with what the adapter can do.
pub struct Gpu {
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Name, driver and backend of the adapter.
    pub info: wgpu::AdapterInfo,
    /// True when GPU timestamp queries are available (per-pass timing).
    pub timestamps: bool,
    /// Bytes mapped back to the CPU so far ([`Gpu::read_buffer`], which every read-back
    /// goes through): lets the viewer show, and its tests prove, that presenting a frame
    /// reads nothing back.
    read_back: std::sync::atomic::AtomicU64,
}

/// What to do when no adapter can render (the CPU Vulkan driver is a package away).
pub const HINT: &str = "no Vulkan adapter found: install a Vulkan driver — on Debian/Ubuntu \
    `apt-get install mesa-vulkan-drivers` (lavapipe, the CPU one) — or run on a machine with a GPU";

/// Why `adapter` cannot run the renderer, if it cannot: every frame is drawn into a linear
/// `Rgba32Float` target (a render attachment that plain OpenGL ES adapters lack).
fn unusable(adapter: &wgpu::Adapter) -> Option<&'static str> {
    let f = adapter.get_texture_format_features(wgpu::TextureFormat::Rgba32Float);
    (!f.allowed_usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT))
        .then_some("cannot render into an Rgba32Float target")
}

/// The most bytes of render targets one frame may take (see [`Gpu::check_frame`]).
pub const MAX_FRAME_TARGET_BYTES: u64 = 3 << 30;

impl Gpu {
    /// Creates a headless device on the first adapter wgpu finds (any backend, software
    /// adapters included) that can render the frame's linear `Rgba32Float` target,
    /// requesting the adapter's own limits so that large texture arrays fit. Without one the
    /// error says what to install (an OpenGL-only machine, e.g. llvmpipe without a Vulkan
    /// driver, has an adapter that cannot render the frame).
    pub fn new() -> Result<Gpu> {
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        };
        // Vulkan/Metal/DX12 first (quietly: GL probing complains without a display), then
        // anything, unless WGPU_BACKEND says otherwise.
        let mut last_err = String::new();
        let mut adapter = None;
        for backends in [wgpu::Backends::PRIMARY, wgpu::Backends::all()] {
            let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
            desc.backends = backends;
            let instance = wgpu::Instance::new(desc.with_env());
            match pollster::block_on(instance.request_adapter(&options)) {
                Ok(a) => {
                    adapter = Some(a);
                    break;
                }
                Err(e) => last_err = e.to_string(),
            }
        }
        let adapter = adapter.ok_or_else(|| Error::NoAdapter(format!("{last_err}; {HINT}")))?;
        if let Some(why) = unusable(&adapter) {
            let info = adapter.get_info();
            return Err(Error::NoAdapter(format!(
                "the only adapter, {} ({:?}), {why}; {HINT}",
                info.name, info.backend
            )));
        }
        Gpu::from_adapter(&adapter)
    }

    /// A device on an adapter that can present to `surface` (created from `instance`), and
    /// the adapter (for the surface's capabilities). Used by the interactive viewer.
    pub fn with_surface(
        instance: &wgpu::Instance,
        surface: &wgpu::Surface,
    ) -> Result<(Gpu, wgpu::Adapter)> {
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(surface),
            ..Default::default()
        };
        let adapter = pollster::block_on(instance.request_adapter(&options))
            .map_err(|e| Error::NoAdapter(e.to_string()))?;
        Ok((Gpu::from_adapter(&adapter)?, adapter))
    }

    /// A device on `adapter` with its own limits and, when offered, timestamp queries.
    pub fn from_adapter(adapter: &wgpu::Adapter) -> Result<Gpu> {
        let available = adapter.features();
        // FLOAT32_BLENDABLE: the thin-cloth pass blends into the f32 colour target.
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::FLOAT32_BLENDABLE;
        let required_features = available & wanted;
        let desc = wgpu::DeviceDescriptor {
            label: Some("btf-render"),
            required_features,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|e| Error::Gpu(format!("request_device: {e}")))?;
        let timestamps = required_features.contains(wgpu::Features::TIMESTAMP_QUERY);
        let read_back = Default::default();
        Ok(Gpu { device, queue, info: adapter.get_info(), timestamps, read_back })
    }

    /// For tests: a device, or `None` (with a message) when no adapter exists. With
    /// `BTF_REQUIRE_GPU=1` a missing adapter is a failure instead (CI sets it).
    pub fn for_tests(test: &str) -> Option<Gpu> {
        match Gpu::new() {
            Ok(g) => Some(g),
            Err(e) => {
                if std::env::var("BTF_REQUIRE_GPU").is_ok_and(|v| v == "1") {
                    panic!("{test}: BTF_REQUIRE_GPU=1 but {e}");
                }
                eprintln!("{test}: skipped, {e}");
                None
            }
        }
    }

    /// Runs `f` inside a validation + out-of-memory error scope and turns a captured error
    /// into [`Error::Gpu`] naming `what`.
    pub fn scoped<T>(&self, what: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let val = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        if let Some(e) = pollster::block_on(val.pop()) {
            return Err(Error::Gpu(format!("{what}: {e}")));
        }
        if let Some(e) = pollster::block_on(oom.pop()) {
            return Err(Error::Gpu(format!("{what}: {e}")));
        }
        Ok(out)
    }

    /// Refuses a frame of `width × height` pixels at `samples` per pixel that this adapter
    /// cannot hold, naming the limit, before anything is allocated: each side against
    /// `max_texture_dimension_2d`, the linear read-back (16 bytes a pixel) against
    /// `max_buffer_size`, and the frame's render targets (colour, depth and corner ids at
    /// `samples`, about 32 bytes a sample) against [`MAX_FRAME_TARGET_BYTES`].
    pub fn check_frame(&self, width: u32, height: u32, samples: u32) -> Result<()> {
        let limits = self.device.limits();
        let side = limits.max_texture_dimension_2d;
        if width > side || height > side {
            return Err(Error::Limit(format!(
                "a {width} × {height} frame exceeds this adapter's max_texture_dimension_2d \
                 ({side}); render at most {side} pixels on a side"
            )));
        }
        let readback = width as u64 * height as u64 * 16;
        if readback > limits.max_buffer_size {
            return Err(Error::Limit(format!(
                "a {width} × {height} frame needs a {readback}-byte read-back buffer, above this \
                 adapter's max_buffer_size ({})",
                limits.max_buffer_size
            )));
        }
        let targets = width as u64 * height as u64 * (16 + 32 * samples.max(1) as u64);
        if targets > MAX_FRAME_TARGET_BYTES {
            return Err(Error::Limit(format!(
                "a {width} × {height} frame at {samples} samples per pixel needs about {} MiB of \
                 render targets, above the {} MiB this renderer allows",
                targets >> 20,
                MAX_FRAME_TARGET_BYTES >> 20
            )));
        }
        Ok(())
    }

    /// Waits until all submitted work is done.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| Error::Gpu(format!("poll: {e}")))
    }

    /// Bytes read back to the CPU by this device so far.
    pub fn read_back_bytes(&self) -> u64 {
        self.read_back.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Maps `buffer` (MAP_READ) and copies its bytes out.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        self.read_back.fetch_add(buffer.size(), std::sync::atomic::Ordering::Relaxed);
        let (tx, rx) = mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| Error::Gpu(format!("map: {e}")))?
            .map_err(|e| Error::Gpu(format!("map: {e}")))?;
        let bytes =
            buffer.get_mapped_range(..).map_err(|e| Error::Gpu(format!("map: {e:?}")))?.to_vec();
        buffer.unmap();
        Ok(bytes)
    }

    /// A 2-D, single-layer, single-mip `width × height` texture of `samples` samples: the
    /// render targets of a frame.
    pub fn target(
        &self,
        label: &str,
        (width, height): (u32, u32),
        samples: u32,
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }

    /// Reads layer 0 of a `width × height` texture with `bytes_per_texel`-byte texels,
    /// returning tightly packed rows.
    pub fn read_texture(&self, texture: &wgpu::Texture, bytes_per_texel: u32) -> Result<Vec<u8>> {
        let (w, h) = (texture.width(), texture.height());
        let unpadded = w * bytes_per_texel;
        let padded = unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (padded * h) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        self.queue.submit([enc.finish()]);
        let raw = self.read_buffer(&buffer)?;
        let mut out = Vec::with_capacity((unpadded * h) as usize);
        for row in raw.chunks_exact(padded as usize) {
            out.extend_from_slice(&row[..unpadded as usize]);
        }
        Ok(out)
    }
}

/// A bind-group layout with one uniform buffer at binding 0, seen by `visibility`.
pub fn uniform_layout(
    dev: &wgpu::Device,
    label: &str,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayout {
    dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

/// Validates WGSL source with naga (parse + full validation), naming the file on failure.
pub fn validate_wgsl(name: &str, source: &str) -> Result<()> {
    use wgpu::naga;
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| Error::Gpu(format!("{name}: {}", e.emit_to_string(source))))?;
    let mut v = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    );
    v.validate(&module).map_err(|e| Error::Gpu(format!("{name}: {}", e.emit_to_string(source))))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headless_device_clears_and_reads_back() {
        let Some(gpu) = Gpu::for_tests("headless_device_clears_and_reads_back") else { return };
        let tex = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d { width: 5, height: 3, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = tex.create_view(&Default::default());
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.25, g: 0.5, b: 2.0, a: 1.0 }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        gpu.queue.submit([enc.finish()]);
        let px: Vec<f32> = bytemuck::cast_slice(&gpu.read_texture(&tex, 16).unwrap()).to_vec();
        assert_eq!(px.len(), 5 * 3 * 4);
        assert_eq!(&px[px.len() - 4..], &[0.25, 0.5, 2.0, 1.0]);
        eprintln!(
            "adapter: {} ({:?}), timestamps {}",
            gpu.info.name, gpu.info.backend, gpu.timestamps
        );
    }
}
