//! Offscreen rendering: the terrain's hierarchy ranges drawn into an `Rgba8Unorm` colour texture with a
//! `Depth32Float` depth buffer (reversed Z), then read back into an [`RgbaImage`].
//!
//! Every [`DrawItem`] is one `draw_indexed` call over its triangle range (indices `3s..3e`), solid or as a wireframe.
//! Read-back copies the texture into a buffer whose rows are padded to a multiple of 256 bytes (wgpu's
//! `COPY_BYTES_PER_ROW_ALIGNMENT`), maps it and waits with `PollType::wait_indefinitely()`. Where the device has
//! pipeline-statistics queries (lavapipe does), a render can also report how many primitives the GPU clipped, so
//! tests can check that it drew exactly the culler's triangles.

use std::time::Instant;

use glam::{Mat4, Vec3};

use crate::error::{Result, ViewerError};
use crate::gpu::Gpu;
use crate::palette;
use crate::scene::{COLOUR_ATTRIBUTES, GpuScene, VERTEX_ATTRIBUTES, flat_vertices};

/// Format of the colour target (the bytes are display values, written unchanged to PNG).
pub const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Format of the depth buffer.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Direction towards the light: from the north-west, 50° above the horizon (the usual hillshade convention).
pub const LIGHT_AZIMUTH_DEG: f32 = 135.0;
/// Elevation of the light above the horizon.
pub const LIGHT_ELEVATION_DEG: f32 = 50.0;
/// Share of a colour kept on a face turned away from the light.
pub const AMBIENT: f32 = 0.5;
/// How far the wireframe of culled groups is lightened towards white.
pub const WIRE_LIGHTEN: f32 = 0.6;
/// The largest image side rendered.
pub const MAX_SIDE: u32 = 8192;

/// The unit vector towards the light.
pub fn light_direction() -> Vec3 {
    crate::camera::direction(LIGHT_AZIMUTH_DEG.to_radians(), LIGHT_ELEVATION_DEG.to_radians())
}

/// The hillshade factor the shader applies to a face with unit normal `normal`.
pub fn hillshade(normal: Vec3) -> f32 {
    AMBIENT + (1.0 - AMBIENT) * normal.normalize_or(Vec3::Z).dot(light_direction()).max(0.0)
}

/// An RGBA8 image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbaImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub pixels: Vec<u8>,
}

impl RgbaImage {
    /// The pixel at `(x, y)`; `None` outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = ((y * self.width + x) * 4) as usize;
        let p = &self.pixels[i..i + 4];
        Some([p[0], p[1], p[2], p[3]])
    }

    /// Counts pixels that differ between `self` and `other` (same size) and draws a difference image: differing
    /// pixels pure red, the rest a darkened grey copy of `self`. `None` when the sizes differ.
    pub fn difference(&self, other: &RgbaImage) -> Option<(RgbaImage, u64)> {
        if (self.width, self.height) != (other.width, other.height) {
            return None;
        }
        let mut count = 0;
        let mut pixels = Vec::with_capacity(self.pixels.len());
        for (a, b) in self.pixels.chunks_exact(4).zip(other.pixels.chunks_exact(4)) {
            if a != b {
                count += 1;
                pixels.extend_from_slice(&[255, 0, 0, 255]);
            } else {
                let luma = (u32::from(a[0]) * 3 + u32::from(a[1]) * 6 + u32::from(a[2])) / 10;
                let g = (luma / 2 + 40) as u8;
                pixels.extend_from_slice(&[g, g, g, 255]);
            }
        }
        Some((
            RgbaImage {
                width: self.width,
                height: self.height,
                pixels,
            },
            count,
        ))
    }

    /// Number of pixels whose colour is exactly `rgba`.
    pub fn count(&self, rgba: [u8; 4]) -> u64 {
        self.pixels.chunks_exact(4).filter(|p| *p == rgba).count() as u64
    }
}

/// How a range is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DrawStyle {
    /// Filled, flat-shaded.
    Solid,
    /// Edges only, lightened towards white (culled groups).
    Wire,
}

/// One indexed draw: a `[start, end)` triangle range in a style.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawItem {
    /// Triangle range (hierarchy order).
    pub range: [u32; 2],
    /// Style.
    pub style: DrawStyle,
}

/// The viewpoint marker: a pin standing on the eye, a thin pole up to an octahedron head, so that a viewpoint
/// down in a valley still shows from afar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Marker {
    /// Eye position (local): the foot of the pin.
    pub position: Vec3,
    /// Radius of the head (m).
    pub size: f32,
    /// Height of the head's centre above the eye (m).
    pub height: f32,
}

/// What one render did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Indexed draw calls of terrain ranges.
    pub draws: u32,
    /// Triangles submitted in those draws.
    pub triangles: u64,
    /// Primitives the GPU's clipper received during the terrain draws (pipeline statistics), when available.
    pub gpu_primitives: Option<u64>,
    /// Vertex shader invocations during the terrain draws (pipeline statistics), when available.
    pub gpu_vertices: Option<u64>,
    /// Wall time from encoding to the GPU's completion (ms).
    pub ms: f64,
}

/// A frame to draw.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// The terrain buffers.
    pub scene: &'a GpuScene,
    /// The camera's clip transform (reversed Z).
    pub view_proj: Mat4,
    /// Ranges to draw, each one indexed draw.
    pub items: &'a [DrawItem],
    /// An optional viewpoint marker.
    pub marker: Option<Marker>,
    /// Count primitives with a pipeline-statistics query (ignored where the device lacks them).
    pub count_primitives: bool,
}

struct Target {
    width: u32,
    height: u32,
    colour: wgpu::Texture,
    view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
}

struct Statistics {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
}

/// Offscreen renderer: pipelines, uniforms and a render target of a given size.
pub struct Renderer {
    solid: wgpu::RenderPipeline,
    wire: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    target: Target,
    statistics: Option<Statistics>,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("width", &self.target.width)
            .field("height", &self.target.height)
            .finish_non_exhaustive()
    }
}

const UNIFORM_BYTES: u64 = 64 + 16 + 16;

impl Renderer {
    /// Creates pipelines and a `width × height` target.
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Result<Renderer> {
        check_size(width, height)?;
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("terrain shader"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("terrain uniforms"),
            size: UNIFORM_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("terrain uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(UNIFORM_BYTES),
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("terrain uniforms"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("terrain"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |fragment: &str| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fragment),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[
                        Some(wgpu::VertexBufferLayout {
                            array_stride: 24,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes: &VERTEX_ATTRIBUTES,
                        }),
                        Some(wgpu::VertexBufferLayout {
                            array_stride: 4,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes: &COLOUR_ATTRIBUTES,
                        }),
                    ],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOUR_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let solid = pipeline("fs_solid");
        let wire = pipeline("fs_wire");
        let statistics = gpu.has_pipeline_statistics().then(|| Statistics {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("primitive count"),
                ty: wgpu::QueryType::PipelineStatistics(
                    wgpu::PipelineStatisticsTypes::VERTEX_SHADER_INVOCATIONS
                        | wgpu::PipelineStatisticsTypes::CLIPPER_INVOCATIONS,
                ),
                count: 1,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("statistics resolve"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("statistics readback"),
                size: 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        });
        Ok(Renderer {
            solid,
            wire,
            uniforms,
            bind_group,
            target: Target::new(gpu, width, height),
            statistics,
        })
    }

    /// The target's size.
    pub fn size(&self) -> [u32; 2] {
        [self.target.width, self.target.height]
    }

    /// Resizes the target (no-op when unchanged).
    pub fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<()> {
        check_size(width, height)?;
        if [width, height] != self.size() {
            self.target = Target::new(gpu, width, height);
        }
        Ok(())
    }

    /// The colour texture, for showing in a UI. Its bytes are display (gamma-encoded) values, which is what egui
    /// expects of a texture that is not sRGB-aware.
    pub fn texture_view(&self) -> &wgpu::TextureView {
        &self.target.view
    }

    /// Draws `frame` and waits for the GPU.
    pub fn render(&mut self, gpu: &Gpu, frame: &Frame<'_>) -> Result<FrameStats> {
        let start = Instant::now();
        let device = &gpu.device;
        let mut uniforms = [0f32; 24];
        uniforms[..16].copy_from_slice(&frame.view_proj.to_cols_array());
        uniforms[16..19].copy_from_slice(&light_direction().to_array());
        uniforms[20] = AMBIENT;
        uniforms[21] = WIRE_LIGHTEN;
        gpu.queue
            .write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&uniforms));
        let marker = frame.marker.map(|m| {
            let (vertices, colours) = marker_mesh(&m);
            let buffer = |label, contents: &[u8]| {
                wgpu::util::DeviceExt::create_buffer_init(
                    device,
                    &wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents,
                        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::INDEX,
                    },
                )
            };
            let indices: Vec<u32> = (0..vertices.len() as u32).collect();
            (
                buffer("marker vertices", bytemuck::cast_slice(&vertices)),
                buffer("marker colours", bytemuck::cast_slice(&colours)),
                buffer("marker indices", bytemuck::cast_slice(&indices)),
                indices.len() as u32,
            )
        });
        let stats_query = self.statistics.as_ref().filter(|_| frame.count_primitives);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("terrain frame"),
        });
        let mut stats = FrameStats::default();
        {
            let bg = palette::BACKGROUND;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("terrain"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.target.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: bg[0],
                            g: bg[1],
                            b: bg[2],
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.target.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.bind_group, &[]);
            let scene = frame.scene;
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            pass.set_vertex_buffer(1, scene.colours.slice(..));
            pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            if let Some(q) = stats_query {
                pass.begin_pipeline_statistics_query(&q.queries, 0);
            }
            for style in [DrawStyle::Solid, DrawStyle::Wire] {
                pass.set_pipeline(match style {
                    DrawStyle::Solid => &self.solid,
                    DrawStyle::Wire => &self.wire,
                });
                for item in frame.items.iter().filter(|i| i.style == style) {
                    let [s, e] = item.range;
                    if s >= e || e > scene.triangles {
                        continue;
                    }
                    pass.draw_indexed(s * 3..e * 3, 0, 0..1);
                    stats.draws += 1;
                    stats.triangles += u64::from(e - s);
                }
            }
            if stats_query.is_some() {
                pass.end_pipeline_statistics_query();
            }
            if let Some((vertices, colours, indices, count)) = &marker {
                pass.set_pipeline(&self.solid);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_vertex_buffer(1, colours.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..*count, 0, 0..1);
            }
        }
        if let Some(q) = stats_query {
            encoder.resolve_query_set(&q.queries, 0..1, &q.resolve, 0);
            encoder.copy_buffer_to_buffer(&q.resolve, 0, &q.readback, 0, 16);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait()?;
        stats.ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(q) = stats_query {
            let bytes = read_buffer(gpu, &q.readback, 16)?;
            let word = |i: usize| {
                let mut w = [0u8; 8];
                w.copy_from_slice(&bytes[i * 8..i * 8 + 8]);
                u64::from_le_bytes(w)
            };
            // Results come in the order of the flag bits: vertex shader invocations, then clipper invocations.
            stats.gpu_vertices = Some(word(0));
            stats.gpu_primitives = Some(word(1));
        }
        Ok(stats)
    }

    /// Reads the colour target back.
    pub fn read_image(&self, gpu: &Gpu) -> Result<RgbaImage> {
        let (width, height) = (self.target.width, self.target.height);
        let row = width * 4;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let size = u64::from(padded) * u64::from(height);
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("image readback"),
        });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.target.colour,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        gpu.queue.submit([encoder.finish()]);
        let bytes = read_buffer(gpu, &buffer, size)?;
        let mut pixels = Vec::with_capacity((row * height) as usize);
        for y in 0..height as usize {
            let at = y * padded as usize;
            pixels.extend_from_slice(&bytes[at..at + row as usize]);
        }
        Ok(RgbaImage { width, height, pixels })
    }
}

fn check_size(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(ViewerError::Invalid(format!(
            "image size {width}x{height} is out of range 1..={MAX_SIDE}"
        )));
    }
    Ok(())
}

impl Target {
    fn new(gpu: &Gpu, width: u32, height: u32) -> Target {
        let extent = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let colour = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("terrain colour"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: COLOUR_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let depth = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("terrain depth"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let view = colour.create_view(&Default::default());
        Target {
            width,
            height,
            colour,
            view,
            depth_view: depth.create_view(&Default::default()),
        }
    }
}

/// Maps `buffer` (already submitted to be filled), waits, and copies its first `size` bytes out.
fn read_buffer(gpu: &Gpu, buffer: &wgpu::Buffer, size: u64) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, ..size, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv()
        .map_err(|e| ViewerError::Gpu(format!("buffer map never completed: {e}")))?
        .map_err(|e| ViewerError::Gpu(format!("cannot map a buffer: {e}")))?;
    let bytes = {
        let view = buffer
            .get_mapped_range(..size)
            .map_err(|e| ViewerError::Gpu(format!("cannot read a mapped buffer: {e}")))?;
        view.to_vec()
    };
    buffer.unmap();
    Ok(bytes)
}

/// The marker's triangles (unshared vertices with face normals) and their colours.
fn marker_mesh(m: &Marker) -> (Vec<[f32; 6]>, Vec<[u8; 4]>) {
    let r = m.size.max(1e-3);
    let c = m.position + Vec3::Z * m.height.max(0.0);
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    // The head: an octahedron.
    let tips = [
        c + Vec3::X * r,
        c + Vec3::Y * r,
        c - Vec3::X * r,
        c - Vec3::Y * r,
        c + Vec3::Z * r,
        c - Vec3::Z * r,
    ];
    positions.extend(tips.iter().map(|p| p.to_array()));
    for k in 0..4u32 {
        let next = (k + 1) % 4;
        triangles.push([k, next, 4]);
        triangles.push([next, k, 5]);
    }
    // The pole: a thin square prism from the eye up to the head.
    let w = r * 0.2;
    let base = positions.len() as u32;
    for z in [m.position.z, c.z] {
        for (dx, dy) in [(w, w), (-w, w), (-w, -w), (w, -w)] {
            positions.push([c.x + dx, c.y + dy, z]);
        }
    }
    for k in 0..4u32 {
        let next = (k + 1) % 4;
        let (a, b, a2, b2) = (base + k, base + next, base + 4 + k, base + 4 + next);
        triangles.push([a, b, b2]);
        triangles.push([a, b2, a2]);
    }
    let vertices = flat_vertices(&positions, &triangles);
    let colour = palette::to_rgba8(palette::MARKER_COLOUR);
    (vertices, vec![colour; triangles.len() * 3])
}
