//! Headless rendering (`partscene render`, image tests): a wgpu device without a window. On a
//! machine without a GPU, Mesa's lavapipe (software Vulkan, Debian `mesa-vulkan-drivers`) serves.

use std::path::Path;
use std::sync::mpsc;
use std::time::Duration;

use image::RgbaImage;

use super::camera::OrbitCamera;
use super::draw::DrawData;
use super::gpu::{FrameParams, SceneRenderer};

/// Why a headless render failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(
        "no GPU adapter: {0} (on a machine without a GPU install Mesa's software Vulkan: `apt-get install mesa-vulkan-drivers libvulkan1`)"
    )]
    NoAdapter(String),
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    #[error("GPU read-back failed: {0}")]
    ReadBack(String),
    #[error("cannot write {path}: {message}")]
    Write { path: String, message: String },
}

/// A headless GPU device.
pub struct Headless {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// Adapter name and backend, for messages.
    pub adapter: String,
}

impl Headless {
    /// Opens the first adapter wgpu offers without a window (a CPU adapter such as lavapipe is fine).
    pub fn new() -> Result<Self, RenderError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("partscene headless"),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;
        Ok(Self { device, queue, adapter: format!("{} ({:?})", info.name, info.backend) })
    }

    /// Renders `data` seen by `camera` into an image of `size_px`.
    pub fn render(&self, data: &DrawData, camera: &OrbitCamera, size_px: [u32; 2], point_size_px: f32) -> Result<RgbaImage, RenderError> {
        let size_px = [size_px[0].clamp(1, 8192), size_px[1].clamp(1, 8192)];
        let mut renderer = SceneRenderer::new(&self.device, None);
        renderer.upload(&self.device, &self.queue, data, 0);
        let aspect = size_px[0] as f32 / size_px[1] as f32;
        let frame = FrameParams { clip_from_world: camera.clip_from_world(aspect), eye_world: camera.eye_world(), size_px, point_size_px };
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("render") });
        renderer.render(&self.device, &self.queue, &mut encoder, &frame);
        let texture = renderer.view_texture().ok_or_else(|| RenderError::ReadBack("nothing rendered".into()))?;
        read_back(&self.device, &self.queue, encoder, texture)
    }
}

fn read_back(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mut encoder: wgpu::CommandEncoder,
    texture: &wgpu::Texture,
) -> Result<RgbaImage, RenderError> {
    let (width, height) = (texture.width(), texture.height());
    let unpadded = width as usize * 4;
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize;
    let padded = unpadded.div_ceil(align) * align;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size: (padded * height as usize) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded as u32), rows_per_image: None },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    let submission = queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    let (tx, rx) = mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| drop(tx.send(r)));
    device
        .poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: Some(Duration::from_mins(1)) })
        .map_err(|e| RenderError::ReadBack(e.to_string()))?;
    rx.recv().map_err(|e| RenderError::ReadBack(e.to_string()))?.map_err(|e| RenderError::ReadBack(e.to_string()))?;
    let mapped = slice.get_mapped_range().map_err(|e| RenderError::ReadBack(e.to_string()))?;
    let pixels: Vec<u8> = mapped.chunks_exact(padded).flat_map(|row| row[..unpadded].iter().copied()).collect();
    drop(mapped);
    RgbaImage::from_raw(width, height, pixels).ok_or_else(|| RenderError::ReadBack("short read".into()))
}

/// Writes `image` as PNG atomically.
pub fn save_png(image: &RgbaImage, path: &Path) -> Result<(), RenderError> {
    let mut bytes = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| RenderError::Write { path: path.display().to_string(), message: e.to_string() })?;
    crate::io::atomic_write(path, &bytes).map_err(|e| RenderError::Write { path: path.display().to_string(), message: e.to_string() })
}
