//! glTF 2.0 export of a hierarchy: binary `.glb`, or `.gltf` JSON with a `.bin` beside it.
//!
//! What is written (JSON with `serde_json`, written straight from the hierarchy; the binary buffer little-endian):
//! - **Buffer** (one): positions (f32 VEC3, relative to the hierarchy's local origin), normals (f32 VEC3, per vertex,
//!   area-weighted, unit length), then the triangle indices (u32) in hierarchy order, in three buffer views
//!   (0 positions, 1 normals, 2 indices). Triangle `t` of the hierarchy is indices `3t .. 3t+3` of buffer view 2, so
//!   a triangle range `[s, e)` is the index bytes `12 s .. 12 e`.
//! - **Meshes**: one per leaf group (group `i` is the `i`-th leaf in triangle order, as in the OBJ export), one
//!   primitive each whose index accessor is the group's range of buffer view 2; then one mesh `always_visible` for
//!   the always-visible (orphan) triangles when there are any. All primitives share the POSITION and NORMAL
//!   accessors 0 and 1.
//! - **Materials**: the group colours of the OBJ export ([`crate::palette`]), converted from sRGB to the linear
//!   `baseColorFactor` glTF expects, dark grey for the always-visible set; not metallic, fully rough.
//! - **Nodes**: node 0 `terrain` is the root. It turns the terrain's +z up into glTF's +y up (`rotation` −90° about +x:
//!   `(x, y, z) → (x, z, −y)`, so north is −z) and moves it to its local origin (`translation`: the origin turned the
//!   same way, written exactly as f64: a reader that keeps f64 places the scene where the culler's world frame puts it,
//!   one that keeps f32 rounds it, up to 0.25 m at UTM northings); the buffer and `extras` keep the terrain's own axes.
//!   Hierarchy node `i` is glTF node `i + 1`, with the children of the hierarchy as its children and, for a leaf, its
//!   group's mesh; the hierarchy's top-level nodes and, when there are always-visible triangles, a last node
//!   `always_visible` (with their mesh) are the children of node 0.
//! - **Culling data** in `extras.tincull` (documented here; no extension is required to load the file):
//!   - on the scene: `{"version": 1, "sectors", "origin": [x, y, z] (exact f64), "roots": [hierarchy node indices],
//!     "always_visible": [s, e], "triangles", "vertices", "node_offset": 1, "index_buffer_view": 2, "build": {...}}`;
//!   - on each hierarchy node's glTF node: `{"index": i, "centre": [x, y], "radius", "children": [...],
//!     "triangles": [s, e], "level", "regions": [{"sector", "points": [[t, z], ...], "tail_slope"}]}`, the same
//!     fields and values as the `.tch` file (and its JSON form), so a loader can rebuild the [`cull::Hierarchy`]
//!     without the `.tch` ([`hierarchy_from_gltf_json`] does exactly that, positions from the f32 buffer).
//!
//! [`gltf_files`] returns the bytes of the files; the caller writes them (the CLI through its one writer).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use cull::{BuildInfo, Hierarchy, Mesh, Node};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Serialize, Serializer};
use serde_json::Value;

use crate::ExportError;
use crate::palette::{ORPHAN_COLOUR, group_colour};

/// The result of this module's functions.
type Result<T> = std::result::Result<T, ExportError>;

/// Version of the `extras.tincull` layout.
pub const EXTRAS_VERSION: u32 = 1;

const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The glTF JSON document and the binary buffer of `h` (with the buffer's `uri` when given, for `.gltf`). The
/// document is written as it is serialised, straight from the hierarchy: no JSON value tree is built, so it takes
/// little memory beyond the text it writes.
pub fn to_gltf<'a>(h: &'a Hierarchy, buffer_uri: Option<&str>) -> Result<(Document<'a>, Vec<u8>)> {
    let nv = h.mesh.positions.len();
    let nt = h.mesh.triangles.len();
    if nv == 0 || nt == 0 {
        return Err(ExportError::NoTriangles);
    }
    let o = h.origin;
    let positions: Vec<[f32; 3]> = h
        .mesh
        .positions
        .iter()
        .map(|p| [(p[0] - o[0]) as f32, (p[1] - o[1]) as f32, (p[2] - o[2]) as f32])
        .collect();
    let normals = vertex_normals(&h.mesh);
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in &positions {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    let mut bin = Vec::with_capacity(24 * nv + 12 * nt);
    for p in &positions {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for n in &normals {
        for c in n {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in &h.mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let vbytes = 12 * nv;
    let ibytes = 12 * nt;

    let vec3 = |view, min, max| Accessor {
        buffer_view: view,
        byte_offset: None,
        component_type: FLOAT,
        count: nv,
        kind: "VEC3",
        min,
        max,
    };
    let mut accessors = vec![vec3(0, Some(min), Some(max)), vec3(1, None, None)];
    let mut meshes = Vec::new();
    let mut materials = Vec::new();
    let mut add_mesh = |name: String, [s, e]: [u32; 2], colour: [f64; 3]| -> usize {
        let a = accessors.len();
        accessors.push(Accessor {
            buffer_view: 2,
            byte_offset: Some(12 * s as usize),
            component_type: UNSIGNED_INT,
            count: 3 * (e - s) as usize,
            kind: "SCALAR",
            min: None,
            max: None,
        });
        let m = materials.len();
        let [r, g, b] = colour.map(srgb_to_linear);
        materials.push(Material {
            name: name.clone(),
            pbr_metallic_roughness: Pbr {
                base_color_factor: [r, g, b, 1.0],
                metallic_factor: 0.0,
                roughness_factor: 1.0,
            },
        });
        meshes.push(GltfMesh {
            name,
            primitives: [Primitive {
                attributes: Attributes { position: 0, normal: 1 },
                indices: a,
                material: m,
                mode: TRIANGLES,
            }],
        });
        meshes.len() - 1
    };

    let leaves = h.leaf_ranges();
    let mut leaf_mesh = HashMap::new();
    for (i, &range) in leaves.iter().enumerate() {
        if range[1] > range[0] {
            let m = add_mesh(format!("group_{i}"), range, group_colour(i));
            leaf_mesh.insert(range, (i, m));
        }
    }
    let av = h.always_visible;
    let always_visible_mesh = (av[1] > av[0]).then(|| add_mesh("always_visible".into(), av, ORPHAN_COLOUR));

    let doc = Document {
        asset: Asset {
            version: "2.0",
            generator: concat!("tincull ", env!("CARGO_PKG_VERSION")),
        },
        scene: 0,
        scenes: [Scene {
            name: "tincull hierarchy",
            nodes: [0],
            extras: Extras {
                tincull: SceneCull {
                    version: EXTRAS_VERSION,
                    sectors: h.sectors,
                    origin: h.origin,
                    roots: &h.roots,
                    always_visible: h.always_visible,
                    triangles: nt,
                    vertices: nv,
                    node_offset: 1,
                    index_buffer_view: 2,
                    build: &h.build,
                },
            },
        }],
        nodes: Nodes {
            h,
            leaf_mesh,
            always_visible_mesh,
        },
        meshes,
        materials,
        accessors,
        buffer_views: [
            BufferView {
                buffer: 0,
                byte_offset: 0,
                byte_length: vbytes,
                target: ARRAY_BUFFER,
            },
            BufferView {
                buffer: 0,
                byte_offset: vbytes,
                byte_length: vbytes,
                target: ARRAY_BUFFER,
            },
            BufferView {
                buffer: 0,
                byte_offset: 2 * vbytes,
                byte_length: ibytes,
                target: ELEMENT_ARRAY_BUFFER,
            },
        ],
        buffers: [Buffer {
            byte_length: bin.len(),
            uri: buffer_uri.map(str::to_owned),
        }],
    };
    Ok((doc, bin))
}

/// The binary glTF (`.glb`) bytes of `h`.
pub fn to_glb(h: &Hierarchy) -> Result<Vec<u8>> {
    let (doc, mut bin) = to_gltf(h, None)?;
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let json_len = json_length(&doc, false)?.next_multiple_of(4);
    let total = 12 + 8 + json_len + 8 + bin.len();
    let total = u32::try_from(total).map_err(|_| ExportError::TooLargeForGlb)?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    // Both fit: each is less than `total`.
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    serde_json::to_writer(&mut out, &doc).map_err(ExportError::json("cannot encode the glTF document"))?;
    out.resize(20 + json_len, b' ');
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}

/// The length of `doc`'s JSON text (`pretty` or compact), counted without keeping it: the text is then written once
/// into a buffer of its size, never into one that grows by copies.
fn json_length(doc: &Document<'_>, pretty: bool) -> Result<usize> {
    /// A writer that keeps only the count of the bytes written to it.
    struct Count(usize);
    impl std::io::Write for Count {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0 += buf.len();
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    let mut count = Count(0);
    if pretty {
        serde_json::to_writer_pretty(&mut count, doc)
    } else {
        serde_json::to_writer(&mut count, doc)
    }
    .map_err(ExportError::json("cannot encode the glTF document"))?;
    Ok(count.0)
}

/// The files of `h` as glTF for `path`: the `.glb` alone when `path` ends in `.glb` (any case), else the `.gltf`
/// JSON and the `.bin` buffer beside it (same stem; the JSON names it by its file name). The caller writes them (the
/// CLI through its one output writer, all or none).
pub fn gltf_files(h: &Hierarchy, path: &Path) -> Result<Vec<(PathBuf, Vec<u8>)>> {
    if is_glb(path) {
        return Ok(vec![(path.to_path_buf(), to_glb(h)?)]);
    }
    let (bin_path, uri) = bin_path(path)?;
    let (doc, bin) = to_gltf(h, Some(&uri))?;
    let mut text = Vec::with_capacity(json_length(&doc, true)?);
    serde_json::to_writer_pretty(&mut text, &doc).map_err(ExportError::json("cannot encode the glTF document"))?;
    Ok(vec![(path.to_path_buf(), text), (bin_path, bin)])
}

/// Whether `path` asks for binary glTF (`.glb`, any case).
pub fn is_glb(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"))
}

/// The `.bin` beside a `.gltf` file and the `uri` that names it; refused when `path` itself ends in `.bin`.
pub fn bin_path(path: &Path) -> Result<(PathBuf, String)> {
    let refuse = |reason| ExportError::Path {
        path: path.to_path_buf(),
        reason,
    };
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("bin")) {
        return Err(refuse("a .gltf output cannot end in .bin, which is its buffer's name"));
    }
    let bin = path.with_extension("bin");
    let uri = bin
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| refuse("the glTF path has no file name"))?;
    Ok((bin, uri))
}

/// Rebuilds the hierarchy from a glTF document written by [`to_gltf`] and its binary buffer: nodes, roots, regions
/// and ranges from `extras.tincull`, the mesh from the buffer (positions are the f32 values plus the exact origin).
/// This is what a loader does to cull without the `.tch`; errors name the element that is missing or malformed.
pub fn hierarchy_from_gltf_json(doc: &Value, bin: &[u8]) -> Result<Hierarchy> {
    let scene = &doc["scenes"][0]["extras"]["tincull"];
    if scene["version"].as_u64() != Some(u64::from(EXTRAS_VERSION)) {
        return Err(ExportError::Malformed(format!(
            "scenes[0].extras.tincull.version is not {EXTRAS_VERSION}: not a tincull glTF"
        )));
    }
    // A field of the scene's extras, decoded; an error naming it when it is missing or malformed.
    fn field<T: serde::de::DeserializeOwned>(scene: &Value, name: &str) -> Result<T> {
        let element = format!("scenes[0].extras.tincull.{name}");
        let Some(v) = scene.get(name) else {
            return Err(ExportError::Malformed(format!("{element} is missing")));
        };
        T::deserialize(v).map_err(ExportError::json(element))
    }
    let sectors: u32 = field(scene, "sectors")?;
    let origin: [f64; 3] = field(scene, "origin")?;
    let roots: Vec<u32> = field(scene, "roots")?;
    let always_visible: [u32; 2] = field(scene, "always_visible")?;
    let nv: usize = field(scene, "vertices")?;
    let nt: usize = field(scene, "triangles")?;
    let build = field(scene, "build")?;
    let mut nodes: Vec<(usize, Node)> = Vec::new();
    let Some(gltf_nodes) = doc["nodes"].as_array() else {
        return Err(ExportError::Malformed("the document has no nodes array".into()));
    };
    for (k, n) in gltf_nodes.iter().enumerate() {
        if let Some(e) = n.get("extras").and_then(|e| e.get("tincull")) {
            let index = usize::deserialize(&e["index"])
                .map_err(ExportError::json(format!("nodes[{k}].extras.tincull.index")))?;
            let node = Node::deserialize(e).map_err(ExportError::json(format!("nodes[{k}].extras.tincull")))?;
            nodes.push((index, node));
        }
    }
    nodes.sort_by_key(|(i, _)| *i);
    if nodes.iter().enumerate().any(|(k, (i, _))| k != *i) {
        return Err(ExportError::Malformed(format!(
            "the hierarchy nodes' extras.tincull.index values are not 0..{}",
            nodes.len()
        )));
    }
    let too_large = || {
        ExportError::Malformed(format!(
            "{nv} vertices and {nt} triangles are more than a buffer can hold"
        ))
    };
    let pos_len = nv.checked_mul(12).ok_or_else(too_large)?;
    let idx_len = nt.checked_mul(12).ok_or_else(too_large)?;
    let need = pos_len
        .checked_mul(2)
        .and_then(|p| p.checked_add(idx_len))
        .ok_or_else(too_large)?;
    if bin.len() < need {
        return Err(ExportError::Malformed(format!(
            "the buffer holds {} bytes, fewer than {nv} vertices and {nt} triangles need",
            bin.len()
        )));
    }
    let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let u = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let positions = bin[..pos_len]
        .chunks_exact(12)
        .map(|c| {
            [
                origin[0] + f64::from(f(&c[0..4])),
                origin[1] + f64::from(f(&c[4..8])),
                origin[2] + f64::from(f(&c[8..12])),
            ]
        })
        .collect();
    let triangles = bin[2 * pos_len..2 * pos_len + idx_len]
        .chunks_exact(12)
        .map(|c| [u(&c[0..4]), u(&c[4..8]), u(&c[8..12])])
        .collect();
    let h = Hierarchy {
        sectors,
        origin,
        nodes: nodes.into_iter().map(|(_, n)| n).collect(),
        roots,
        always_visible,
        mesh: Mesh { positions, triangles },
        build,
    };
    h.check_invariants()?;
    Ok(h)
}

/// glTF primitive mode: triangles.
const TRIANGLES: u32 = 4;

/// The glTF JSON document [`to_gltf`] makes, borrowing the hierarchy: serialise it (with `serde_json`) to get the
/// text, or to a [`serde_json::Value`] to edit it.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Document<'a> {
    asset: Asset,
    scene: u32,
    scenes: [Scene<'a>; 1],
    nodes: Nodes<'a>,
    meshes: Vec<GltfMesh>,
    materials: Vec<Material>,
    accessors: Vec<Accessor>,
    buffer_views: [BufferView; 3],
    buffers: [Buffer; 1],
}

/// The document's `asset`.
#[derive(Serialize)]
struct Asset {
    version: &'static str,
    generator: &'static str,
}

/// The one scene, with the hierarchy's own fields in `extras.tincull`.
#[derive(Serialize)]
struct Scene<'a> {
    name: &'static str,
    nodes: [u32; 1],
    extras: Extras<SceneCull<'a>>,
}

/// An `extras` object holding tincull's data.
#[derive(Serialize)]
struct Extras<T> {
    tincull: T,
}

/// The scene's `extras.tincull` (see the module docs).
#[derive(Serialize)]
struct SceneCull<'a> {
    version: u32,
    sectors: u32,
    origin: [f64; 3],
    roots: &'a [u32],
    always_visible: [u32; 2],
    triangles: usize,
    vertices: usize,
    node_offset: u32,
    index_buffer_view: u32,
    build: &'a BuildInfo,
}

/// A hierarchy node's `extras.tincull`: its index and the node's own fields, as in the `.tch` JSON form.
#[derive(Serialize)]
struct NodeCull<'a> {
    index: usize,
    #[serde(flatten)]
    node: &'a Node,
}

/// The document's nodes, written one at a time from the hierarchy when serialised (see the module docs).
struct Nodes<'a> {
    h: &'a Hierarchy,
    /// Leaf group number and mesh index of each non-empty leaf range.
    leaf_mesh: HashMap<[u32; 2], (usize, usize)>,
    /// The always-visible triangles' mesh, when there are any.
    always_visible_mesh: Option<usize>,
}

/// One glTF node.
#[derive(Serialize)]
struct GltfNode<'a> {
    name: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    rotation: Option<[f32; 4]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    translation: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    children: Vec<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mesh: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    extras: Option<Extras<NodeCull<'a>>>,
}

impl Serialize for Nodes<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let h = self.h;
        let n = h.nodes.len();
        let mut seq = serializer.serialize_seq(Some(n + 1 + usize::from(self.always_visible_mesh.is_some())))?;
        let mut children: Vec<usize> = h.roots.iter().map(|&r| r as usize + 1).collect();
        if self.always_visible_mesh.is_some() {
            children.push(n + 1);
        }
        // glTF is +Y up, the terrain +Z up: node 0 turns it by −90° about +x, `(x, y, z) → (x, z, −y)`, after moving
        // it to its origin (glTF applies the rotation first, so the translation is the origin turned the same way).
        let half = std::f32::consts::FRAC_1_SQRT_2;
        let o = h.origin;
        seq.serialize_element(&GltfNode {
            name: "terrain".into(),
            rotation: Some([-half, 0.0, 0.0, half]),
            translation: Some([o[0], o[2], -o[1]]),
            children,
            mesh: None,
            extras: None,
        })?;
        for (index, node) in h.nodes.iter().enumerate() {
            let leaf = if node.children.is_empty() {
                self.leaf_mesh.get(&node.triangles)
            } else {
                None
            };
            seq.serialize_element(&GltfNode {
                name: match leaf {
                    Some((g, _)) => format!("group_{g}"),
                    None => format!("node_{index}"),
                },
                rotation: None,
                translation: None,
                children: node.children.iter().map(|&c| c as usize + 1).collect(),
                mesh: leaf.map(|&(_, m)| m),
                extras: Some(Extras {
                    tincull: NodeCull { index, node },
                }),
            })?;
        }
        if let Some(m) = self.always_visible_mesh {
            seq.serialize_element(&GltfNode {
                name: "always_visible".into(),
                rotation: None,
                translation: None,
                children: Vec::new(),
                mesh: Some(m),
                extras: None,
            })?;
        }
        seq.end()
    }
}

/// A glTF mesh of one primitive.
#[derive(Serialize)]
struct GltfMesh {
    name: String,
    primitives: [Primitive; 1],
}

/// A triangle primitive over the shared POSITION and NORMAL accessors.
#[derive(Serialize)]
struct Primitive {
    attributes: Attributes,
    indices: usize,
    material: usize,
    mode: u32,
}

/// A primitive's vertex attributes: accessor indices.
#[derive(Serialize)]
#[serde(rename_all = "UPPERCASE")]
struct Attributes {
    position: usize,
    normal: usize,
}

/// A group's material.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Material {
    name: String,
    pbr_metallic_roughness: Pbr,
}

/// A material's metallic-roughness model (linear colour).
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Pbr {
    base_color_factor: [f64; 4],
    metallic_factor: f64,
    roughness_factor: f64,
}

/// A glTF accessor.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Accessor {
    buffer_view: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    byte_offset: Option<usize>,
    component_type: u32,
    count: usize,
    #[serde(rename = "type")]
    kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    min: Option<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    max: Option<[f32; 3]>,
}

/// A glTF buffer view.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct BufferView {
    buffer: u32,
    byte_offset: usize,
    byte_length: usize,
    target: u32,
}

/// The one glTF buffer (its `uri` for `.gltf`).
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Buffer {
    byte_length: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    uri: Option<String>,
}

/// Unit vertex normals: the area-weighted sum of the incident triangles' normals (straight up when degenerate).
fn vertex_normals(mesh: &Mesh) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        for &i in t {
            for k in 0..3 {
                acc[i as usize][k] += n[k];
            }
        }
    }
    acc.into_iter()
        .map(|n| {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if len > 0.0 && len.is_finite() {
                [(n[0] / len) as f32, (n[1] / len) as f32, (n[2] / len) as f32]
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect()
}

/// sRGB-encoded display value to linear.
fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
