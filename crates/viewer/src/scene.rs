//! The terrain as the GPU sees it: f32 positions relative to a local origin (the hierarchy's, or the TIN's), the
//! triangles in hierarchy order, per-triangle colours and face normals.
//!
//! Vertices are not shared between triangles: every triangle has its own three vertices, carrying the triangle's
//! face normal (flat shading) and colour, so that a group boundary never blends two colours. The index buffer is
//! therefore the identity `0..3n`, and a hierarchy range `[s, e)` of triangles is the index range `3s..3e`: one
//! indexed draw per range, exactly as an engine would draw the culler's output. The vertex shader derives each
//! corner's barycentric coordinate from `vertex_index % 3` for the wireframe.

use cull::Hierarchy;
use tin::Tin;
use wgpu::util::DeviceExt;

use crate::error::{Result, ViewerError};
use crate::gpu::Gpu;
use crate::palette;

/// How triangles are coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourMode {
    /// One colour per leaf group (the grouped OBJ's colours), orphans dark grey.
    Groups,
    /// One colour per node at a hierarchy level: each triangle takes the colour of its highest ancestor whose
    /// level is at most the chosen level; orphans dark grey.
    Level,
    /// Drawn (pale green) or culled (slate blue) for a viewpoint.
    Visibility,
    /// Height ramp (the only colouring of a plain mesh).
    Height,
}

impl std::str::FromStr for ColourMode {
    type Err = ViewerError;

    fn from_str(s: &str) -> Result<ColourMode> {
        match s {
            "groups" => Ok(ColourMode::Groups),
            "level" => Ok(ColourMode::Level),
            "visibility" => Ok(ColourMode::Visibility),
            "height" => Ok(ColourMode::Height),
            _ => Err(ViewerError::Invalid(format!(
                "unknown colouring {s:?}: expected groups, level, visibility or height"
            ))),
        }
    }
}

/// The terrain on the CPU side: local f32 geometry and, for a hierarchy, which leaf group each triangle is in.
#[derive(Clone, Debug)]
pub struct Terrain {
    /// Local origin (world coordinates) subtracted from every position.
    pub origin: [f64; 3],
    /// Vertex positions relative to `origin`.
    pub positions: Vec<[f32; 3]>,
    /// Counter-clockwise triangles (hierarchy order when there is a hierarchy).
    pub triangles: Vec<[u32; 3]>,
    /// The hierarchy, if the terrain came from one.
    pub hierarchy: Option<Hierarchy>,
    /// Per triangle: the index of its leaf group in triangle order (the grouped OBJ's `group_N`), or `u32::MAX`
    /// for orphans and plain meshes.
    pub group_of: Vec<u32>,
    /// Number of leaf groups.
    pub groups: usize,
    /// Lower corner of the bounding box (local).
    pub min: [f32; 3],
    /// Upper corner of the bounding box (local).
    pub max: [f32; 3],
}

impl Terrain {
    /// The terrain of a hierarchy (its reordered mesh, relative to the hierarchy's origin).
    pub fn from_hierarchy(h: Hierarchy) -> Result<Terrain> {
        h.check_invariants()?;
        let mut t = Terrain::from_geometry(h.origin, &h.mesh.positions, h.mesh.triangles.clone())?;
        let leaves = h.leaf_ranges();
        for (i, [s, e]) in leaves.iter().enumerate() {
            t.group_of[*s as usize..*e as usize].fill(i as u32);
        }
        t.groups = leaves.len();
        t.hierarchy = Some(h);
        Ok(t)
    }

    /// The terrain of a plain mesh, relative to the TIN's local origin.
    pub fn from_tin(tin: &Tin) -> Result<Terrain> {
        let o = tin.origin();
        let positions: Vec<[f64; 3]> = tin.positions().iter().map(|p| [p.x, p.y, p.z]).collect();
        Terrain::from_geometry([o.x, o.y, o.z], &positions, tin.triangles().to_vec())
    }

    fn from_geometry(origin: [f64; 3], world: &[[f64; 3]], triangles: Vec<[u32; 3]>) -> Result<Terrain> {
        if triangles.is_empty() {
            return Err(ViewerError::Invalid("the terrain has no triangles".into()));
        }
        if let Some(t) = triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= world.len()))
        {
            return Err(ViewerError::Invalid(format!(
                "triangle {t} refers to a vertex beyond {}",
                world.len()
            )));
        }
        let positions: Vec<[f32; 3]> = world
            .iter()
            .map(|p| {
                [
                    (p[0] - origin[0]) as f32,
                    (p[1] - origin[1]) as f32,
                    (p[2] - origin[2]) as f32,
                ]
            })
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(ViewerError::Invalid(format!("vertex {i} is not finite")));
        }
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for t in &triangles {
            for &v in t {
                let p = positions[v as usize];
                for k in 0..3 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                }
            }
        }
        let n = triangles.len();
        Ok(Terrain {
            origin,
            positions,
            triangles,
            hierarchy: None,
            group_of: vec![u32::MAX; n],
            groups: 0,
            min,
            max,
        })
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The highest hierarchy level (0 without a hierarchy).
    pub fn max_level(&self) -> u32 {
        self.hierarchy
            .as_ref()
            .and_then(|h| h.nodes.iter().map(|n| n.level).max())
            .unwrap_or(0)
    }

    /// A world point in local f32 coordinates.
    pub fn to_local(&self, p: [f64; 3]) -> [f32; 3] {
        [
            (p[0] - self.origin[0]) as f32,
            (p[1] - self.origin[1]) as f32,
            (p[2] - self.origin[2]) as f32,
        ]
    }

    /// A local point in world coordinates.
    pub fn to_world(&self, p: [f32; 3]) -> [f64; 3] {
        [
            f64::from(p[0]) + self.origin[0],
            f64::from(p[1]) + self.origin[1],
            f64::from(p[2]) + self.origin[2],
        ]
    }

    /// Per-triangle colours for `mode`. `level` picks the level of [`ColourMode::Level`] (default: the top);
    /// `drawn` is the culler's mask for [`ColourMode::Visibility`] (required there). Modes that need a hierarchy
    /// fail on a plain mesh, naming the mode.
    pub fn colours(&self, mode: ColourMode, level: Option<u32>, drawn: Option<&[bool]>) -> Result<Vec<[u8; 4]>> {
        let n = self.num_triangles();
        let need_hierarchy = |what: &str| {
            ViewerError::Invalid(format!(
                "colouring by {what} needs a hierarchy (.tch); a plain mesh can only be coloured by height"
            ))
        };
        let orphan = palette::to_rgba8(palette::ORPHAN_COLOUR);
        match mode {
            ColourMode::Groups => {
                if self.hierarchy.is_none() {
                    return Err(need_hierarchy("groups"));
                }
                let table: Vec<[u8; 4]> = (0..self.groups)
                    .map(|i| palette::to_rgba8(palette::group_colour(i)))
                    .collect();
                Ok(self
                    .group_of
                    .iter()
                    .map(|&g| table.get(g as usize).copied().unwrap_or(orphan))
                    .collect())
            }
            ColourMode::Level => {
                let h = self.hierarchy.as_ref().ok_or_else(|| need_hierarchy("level"))?;
                let level = level.unwrap_or_else(|| self.max_level());
                let mut out = vec![orphan; n];
                let mut units: Vec<u32> = Vec::new();
                let mut stack: Vec<u32> = h.roots.clone();
                while let Some(i) = stack.pop() {
                    let node = &h.nodes[i as usize];
                    if node.level <= level || node.children.is_empty() {
                        units.push(i);
                    } else {
                        stack.extend_from_slice(&node.children);
                    }
                }
                units.sort_unstable_by_key(|&i| h.nodes[i as usize].triangles[0]);
                for (k, &i) in units.iter().enumerate() {
                    let [s, e] = h.nodes[i as usize].triangles;
                    out[s as usize..e as usize].fill(palette::to_rgba8(palette::group_colour(k)));
                }
                Ok(out)
            }
            ColourMode::Visibility => {
                let drawn = drawn
                    .ok_or_else(|| ViewerError::Invalid("colouring by visibility needs a viewpoint (--eye)".into()))?;
                if drawn.len() != n {
                    return Err(ViewerError::Invalid(format!(
                        "visibility mask has {} entries for {n} triangles",
                        drawn.len()
                    )));
                }
                let (d, c) = (
                    palette::to_rgba8(palette::DRAWN_COLOUR),
                    palette::to_rgba8(palette::CULLED_COLOUR),
                );
                Ok(drawn.iter().map(|&v| if v { d } else { c }).collect())
            }
            ColourMode::Height => {
                let (lo, hi) = (self.min[2], self.max[2]);
                let span = (hi - lo).max(f32::MIN_POSITIVE);
                Ok(self
                    .triangles
                    .iter()
                    .map(|t| {
                        let z = t.iter().map(|&v| self.positions[v as usize][2]).sum::<f32>() / 3.0;
                        palette::to_rgba8(palette::height_colour(f64::from((z - lo) / span)))
                    })
                    .collect())
            }
        }
    }
}

/// Paints the triangles set in `mask` with the false-cull red.
pub fn paint_false_culls(colours: &mut [[u8; 4]], mask: &[bool]) {
    let red = palette::to_rgba8(palette::FALSE_CULL_COLOUR);
    for (c, &m) in colours.iter_mut().zip(mask) {
        if m {
            *c = red;
        }
    }
}

/// The vertex layout of slot 0 (`[position; 3], [normal; 3]` as f32, 24 bytes) and of the colours (slot 1, `Unorm8x4`).
pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 2] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
/// The colour attribute (slot 1).
pub const COLOUR_ATTRIBUTES: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![2 => Unorm8x4];

/// Unshared vertices of `triangles`: three per triangle, each `[x, y, z, nx, ny, nz]` with the face normal.
pub fn flat_vertices(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 6]> {
    let mut out = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        let [a, b, c] = t.map(|v| glam::Vec3::from(positions[v as usize]));
        let n = (b - a).cross(c - a).normalize_or(glam::Vec3::Z);
        for p in [a, b, c] {
            out.push([p.x, p.y, p.z, n.x, n.y, n.z]);
        }
    }
    out
}

/// The terrain's buffers on the GPU.
#[derive(Debug)]
pub struct GpuScene {
    /// Three vertices per triangle (see [`flat_vertices`]).
    pub vertices: wgpu::Buffer,
    /// Three RGBA8 colours per triangle.
    pub colours: wgpu::Buffer,
    /// The identity index buffer `0..3n` (u32).
    pub indices: wgpu::Buffer,
    /// Number of triangles.
    pub triangles: u32,
}

impl GpuScene {
    /// Uploads `terrain` with the given per-triangle colours.
    pub fn new(gpu: &Gpu, terrain: &Terrain, colours: &[[u8; 4]]) -> Result<GpuScene> {
        let n = terrain.num_triangles();
        let max = (gpu.device.limits().max_buffer_size / 24 / 3).min(u64::from(u32::MAX / 3));
        if n as u64 > max {
            return Err(ViewerError::Invalid(format!(
                "{n} triangles exceed what this GPU can hold in one buffer ({max})"
            )));
        }
        let vertices = flat_vertices(&terrain.positions, &terrain.triangles);
        let indices: Vec<u32> = (0..(n as u32) * 3).collect();
        let device = &gpu.device;
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("terrain vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("terrain indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let colour_bytes = expand_colours(colours, n)?;
        let colours = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("terrain colours"),
            contents: &colour_bytes,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        Ok(GpuScene {
            vertices,
            colours,
            indices,
            triangles: n as u32,
        })
    }

    /// Replaces the per-triangle colours.
    pub fn set_colours(&self, gpu: &Gpu, colours: &[[u8; 4]]) -> Result<()> {
        let bytes = expand_colours(colours, self.triangles as usize)?;
        gpu.queue.write_buffer(&self.colours, 0, &bytes);
        Ok(())
    }
}

fn expand_colours(colours: &[[u8; 4]], n: usize) -> Result<Vec<u8>> {
    if colours.len() != n {
        return Err(ViewerError::Invalid(format!(
            "{} colours for {n} triangles",
            colours.len()
        )));
    }
    let mut out = Vec::with_capacity(n * 12);
    for c in colours {
        for _ in 0..3 {
            out.extend_from_slice(c);
        }
    }
    Ok(out)
}
