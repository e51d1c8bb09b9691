//! The wgpu renderer of the 3D view: draws [`DrawData`] into its own multisampled offscreen
//! target (so it needs nothing from the host's render pass: depth, MSAA and format are ours), then
//! either blits that image into egui's pass (the editor) or reads it back (headless rendering).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use super::draw::{DrawData, LineVertex, PointInstance, SolidBatches, SolidInstance};
use super::mesh::{Mesh, MeshVertex, unit_cube, unit_cylinder, unit_sphere};

/// The offscreen colour format: holds sRGB-encoded values (the shader encodes).
pub const VIEW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const SAMPLES: u32 = 4;
/// Background of the 3D view (sRGB).
pub const BACKGROUND: [f64; 4] = [0.13, 0.14, 0.16, 1.0];

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct FrameUniform {
    clip_from_world: [[f32; 4]; 4],
    eye_world: [f32; 4],
    viewport: [f32; 4],
}

/// Camera and viewport of one frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameParams {
    pub clip_from_world: Mat4,
    pub eye_world: Vec3,
    pub size_px: [u32; 2],
    pub point_size_px: f32,
}

struct GpuMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
}

impl GpuMesh {
    fn new(device: &wgpu::Device, mesh: &Mesh, name: &str) -> Self {
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(name),
            contents: bytemuck::cast_slice(&mesh.vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(name),
            contents: bytemuck::cast_slice(&mesh.indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        Self { vertices, indices, index_count: mesh.indices.len() as u32 }
    }
}

/// A vertex/instance buffer that grows as needed.
struct DynBuffer {
    buffer: Option<wgpu::Buffer>,
    len: u32,
    usage: wgpu::BufferUsages,
    name: &'static str,
}

impl DynBuffer {
    fn new(name: &'static str, usage: wgpu::BufferUsages) -> Self {
        Self { buffer: None, len: 0, usage: usage | wgpu::BufferUsages::COPY_DST, name }
    }

    fn upload<T: Pod>(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, items: &[T]) {
        self.len = items.len() as u32;
        if items.is_empty() {
            return;
        }
        let bytes: &[u8] = bytemuck::cast_slice(items);
        match &self.buffer {
            Some(b) if b.size() >= bytes.len() as u64 => queue.write_buffer(b, 0, bytes),
            _ => {
                self.buffer = Some(device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(self.name),
                    contents: bytes,
                    usage: self.usage,
                }));
            }
        }
    }

    fn slice(&self) -> Option<wgpu::BufferSlice<'_>> {
        (self.len > 0).then_some(())?;
        self.buffer.as_ref().map(|b| b.slice(..))
    }
}

struct Batches {
    cubes: DynBuffer,
    cylinders: DynBuffer,
    spheres: DynBuffer,
}

impl Batches {
    fn new() -> Self {
        let u = wgpu::BufferUsages::VERTEX;
        Self { cubes: DynBuffer::new("cubes", u), cylinders: DynBuffer::new("cylinders", u), spheres: DynBuffer::new("spheres", u) }
    }

    fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, b: &SolidBatches) {
        self.cubes.upload(device, queue, &b.cubes);
        self.cylinders.upload(device, queue, &b.cylinders);
        self.spheres.upload(device, queue, &b.spheres);
    }
}

/// The offscreen target: multisampled colour and depth, resolved into a sampleable texture.
struct ViewTarget {
    size_px: [u32; 2],
    msaa: wgpu::TextureView,
    depth: wgpu::TextureView,
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    blit_bind_group: wgpu::BindGroup,
}

/// Pipelines, meshes and buffers of the 3D view. Create once per device.
pub struct SceneRenderer {
    solid_opaque: wgpu::RenderPipeline,
    solid_blended: wgpu::RenderPipeline,
    points: wgpu::RenderPipeline,
    lines: wgpu::RenderPipeline,
    blit: wgpu::RenderPipeline,
    blit_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    frame_buffer: wgpu::Buffer,
    frame_bind_group: wgpu::BindGroup,
    cube: GpuMesh,
    cylinder: GpuMesh,
    sphere: GpuMesh,
    opaque: Batches,
    blended: Batches,
    point_buffer: DynBuffer,
    line_buffer: DynBuffer,
    /// Which draw data is uploaded (the caller's generation counters).
    uploaded: Option<u64>,
    uploaded_points: Option<u64>,
    target: Option<ViewTarget>,
}

fn solid_layout() -> [wgpu::VertexBufferLayout<'static>; 2] {
    const MESH: [wgpu::VertexAttribute; 2] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
    const INSTANCE: [wgpu::VertexAttribute; 8] = wgpu::vertex_attr_array![
        2 => Float32x4, 3 => Float32x4, 4 => Float32x4, 5 => Float32x4,
        6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 9 => Float32x4
    ];
    [
        wgpu::VertexBufferLayout {
            array_stride: size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &MESH,
        },
        wgpu::VertexBufferLayout {
            array_stride: size_of::<SolidInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &INSTANCE,
        },
    ]
}

const POSITION_COLOR: [wgpu::VertexAttribute; 2] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Unorm8x4];

impl SceneRenderer {
    /// `blit_format`: the format of the render pass the view is blitted into (the editor), or
    /// `None` for headless use.
    #[must_use]
    pub fn new(device: &wgpu::Device, blit_format: Option<wgpu::TextureFormat>) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("partscene scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/scene.wgsl").into()),
        });
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
                count: None,
            }],
        });
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: frame_buffer.as_entire_binding() }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });
        let pipeline = |name: &str,
                        vs: &str,
                        fs: &str,
                        buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                        topology: wgpu::PrimitiveTopology,
                        blended: bool| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(name),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(vs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState { topology, ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(!blended),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState { count: SAMPLES, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: VIEW_FORMAT,
                        blend: blended.then_some(wgpu::BlendState::ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let [mesh, inst] = solid_layout();
        let solid_buffers = [Some(mesh), Some(inst)];
        let solid_opaque = pipeline("solid", "vs_solid", "fs_solid", &solid_buffers, wgpu::PrimitiveTopology::TriangleList, false);
        let solid_blended = pipeline("solid blended", "vs_solid", "fs_solid", &solid_buffers, wgpu::PrimitiveTopology::TriangleList, true);
        let point_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: size_of::<PointInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &POSITION_COLOR,
        })];
        let points = pipeline("points", "vs_point", "fs_point", &point_buffers, wgpu::PrimitiveTopology::TriangleList, false);
        let line_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: size_of::<LineVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &POSITION_COLOR,
        })];
        let lines = pipeline("lines", "vs_line", "fs_point", &line_buffers, wgpu::PrimitiveTopology::LineList, false);

        let blit_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("partscene blit.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/blit.wgsl").into()),
        });
        let blit_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let blit_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("blit"),
            bind_group_layouts: &[Some(&blit_layout)],
            immediate_size: 0,
        });
        let blit_target = blit_format.unwrap_or(VIEW_FORMAT);
        let blit = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: Some(&blit_pipeline_layout),
            vertex: wgpu::VertexState {
                module: &blit_shader,
                entry_point: Some("vs_blit"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &blit_shader,
                entry_point: Some(if blit_target.is_srgb() { "fs_blit_to_srgb" } else { "fs_blit" }),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                targets: &[Some(wgpu::ColorTargetState { format: blit_target, blend: None, write_mask: wgpu::ColorWrites::ALL })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("blit"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Self {
            solid_opaque,
            solid_blended,
            points,
            lines,
            blit,
            blit_layout,
            sampler,
            frame_buffer,
            frame_bind_group,
            cube: GpuMesh::new(device, &unit_cube(), "cube"),
            cylinder: GpuMesh::new(device, &unit_cylinder(32), "cylinder"),
            sphere: GpuMesh::new(device, &unit_sphere(12, 24), "sphere"),
            opaque: Batches::new(),
            blended: Batches::new(),
            point_buffer: DynBuffer::new("points", wgpu::BufferUsages::VERTEX),
            line_buffer: DynBuffer::new("lines", wgpu::BufferUsages::VERTEX),
            uploaded: None,
            uploaded_points: None,
            target: None,
        }
    }

    /// Uploads `data` (points included) unless the data of `generation` is already there.
    pub fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &DrawData, generation: u64) {
        self.upload_geometry(device, queue, data, generation);
        self.upload_points(device, queue, &data.points, generation);
    }

    /// Uploads everything of `data` but its points, unless `generation` is already there.
    pub fn upload_geometry(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &DrawData, generation: u64) {
        if self.uploaded == Some(generation) {
            return;
        }
        self.opaque.upload(device, queue, &data.opaque);
        self.blended.upload(device, queue, &data.translucent);
        self.line_buffer.upload(device, queue, &data.lines);
        self.uploaded = Some(generation);
    }

    /// Uploads the scan points, unless those of `generation` are already there (hover changes
    /// the rest of the view, not the points).
    pub fn upload_points(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, points: &[PointInstance], generation: u64) {
        if self.uploaded_points == Some(generation) {
            return;
        }
        self.point_buffer.upload(device, queue, points);
        self.uploaded_points = Some(generation);
    }

    fn ensure_target(&mut self, device: &wgpu::Device, size_px: [u32; 2]) {
        let size_px = [size_px[0].max(1), size_px[1].max(1)];
        if self.target.as_ref().is_some_and(|t| t.size_px == size_px) {
            return;
        }
        let extent = wgpu::Extent3d { width: size_px[0], height: size_px[1], depth_or_array_layers: 1 };
        let texture = |label, format, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let msaa = texture("view msaa", VIEW_FORMAT, SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let depth = texture("view depth", DEPTH_FORMAT, SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let resolved = texture(
            "view",
            VIEW_FORMAT,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
        );
        let resolved_view = resolved.create_view(&wgpu::TextureViewDescriptor::default());
        let blit_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("blit"),
            layout: &self.blit_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&resolved_view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
            ],
        });
        self.target = Some(ViewTarget {
            size_px,
            msaa: msaa.create_view(&wgpu::TextureViewDescriptor::default()),
            depth: depth.create_view(&wgpu::TextureViewDescriptor::default()),
            resolved,
            resolved_view,
            blit_bind_group,
        });
    }

    /// Draws the uploaded data into the offscreen target (resized to `frame.size_px`).
    pub fn render(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder, frame: &FrameParams) {
        self.ensure_target(device, frame.size_px);
        let uniform = FrameUniform {
            clip_from_world: frame.clip_from_world.to_cols_array_2d(),
            eye_world: frame.eye_world.extend(1.0).into(),
            viewport: [frame.size_px[0].max(1) as f32, frame.size_px[1].max(1) as f32, frame.point_size_px, 0.0],
        };
        queue.write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&uniform));
        let Some(target) = &self.target else { return };
        let [r, g, b, a] = BACKGROUND;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target.msaa,
                depth_slice: None,
                resolve_target: Some(&target.resolved_view),
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }), store: wgpu::StoreOp::Discard },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.frame_bind_group, &[]);
        pass.set_pipeline(&self.solid_opaque);
        self.draw_solids(&mut pass, &self.opaque);
        if let Some(points) = self.point_buffer.slice() {
            pass.set_pipeline(&self.points);
            pass.set_vertex_buffer(0, points);
            pass.draw(0..6, 0..self.point_buffer.len);
        }
        if let Some(lines) = self.line_buffer.slice() {
            pass.set_pipeline(&self.lines);
            pass.set_vertex_buffer(0, lines);
            pass.draw(0..self.line_buffer.len, 0..1);
        }
        pass.set_pipeline(&self.solid_blended);
        self.draw_solids(&mut pass, &self.blended);
    }

    fn draw_solids(&self, pass: &mut wgpu::RenderPass<'_>, batches: &Batches) {
        for (mesh, buffer) in [(&self.cube, &batches.cubes), (&self.cylinder, &batches.cylinders), (&self.sphere, &batches.spheres)] {
            let Some(instances) = buffer.slice() else { continue };
            pass.set_vertex_buffer(0, mesh.vertices.slice(..));
            pass.set_vertex_buffer(1, instances);
            pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.index_count, 0, 0..buffer.len);
        }
    }

    /// Draws the last rendered view into `pass` (over its whole viewport).
    pub fn blit(&self, pass: &mut wgpu::RenderPass<'static>) {
        let Some(target) = &self.target else { return };
        pass.set_pipeline(&self.blit);
        pass.set_bind_group(0, &target.blit_bind_group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// The offscreen colour texture of the last render (for read-back).
    #[must_use]
    pub fn view_texture(&self) -> Option<&wgpu::Texture> {
        self.target.as_ref().map(|t| &t.resolved)
    }
}
