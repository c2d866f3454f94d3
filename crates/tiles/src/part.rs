//! Tiles of a mesh (an OBJ terrain rather than a DEM grid): the plan cuts the whole TIN once and writes each tile's
//! part, which its job reads alone.
//!
//! A triangle belongs to the tile (a square of `tile` metres over the footprint) that holds its centroid; a tile's
//! vertices are its triangles' vertices, so the tiles' triangles are exactly the mesh's, and the merge joins the
//! shared vertices (same positions) back into the same mesh. A part also carries the points its horizons see
//! beyond the tile: every other vertex within `halo` metres of the tile's vertices' bounding box, and the far
//! field outside that: per square of `far_block` metres its lowest vertex, the squares growing with distance as a
//! DEM's blocks do ([`crate::far_field`]). These are vertices of the mesh itself,
//! so they lie on the terrain. The parts of a plan without regions, whose tiles sweep no horizons, carry neither.

use serde::{Deserialize, Serialize};
use tin::Tin;

use crate::TilesError;
use crate::far_field::{Choice, MinPyramid};

/// Magic bytes of a part file (framed like a `.tch`: [`cull::file::frame`]).
pub const PART_MAGIC: &[u8; 8] = b"TCPART\0\0";
/// Version of the part format.
pub const PART_VERSION: u32 = 1;

/// One tile of a mesh: its triangles and the points beyond it that its horizons see.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshPart {
    /// The tile's vertices (world coordinates), in the mesh's vertex order.
    pub positions: Vec<[f64; 3]>,
    /// The tile's triangles, indices into `positions`, in the mesh's triangle order.
    pub triangles: Vec<[u32; 3]>,
    /// Other vertices of the mesh near the tile.
    pub halo: Vec<[f64; 3]>,
    /// Far-field vertices.
    pub far: Vec<[f64; 3]>,
}

impl MeshPart {
    /// The part as a checksummed file.
    pub fn to_bytes(&self) -> Result<Vec<u8>, TilesError> {
        crate::framed::encode(PART_MAGIC, PART_VERSION, self, "a part")
    }

    /// Reads a part file; `name` names it in errors.
    pub fn from_bytes(bytes: &[u8], name: &std::path::Path) -> Result<MeshPart, TilesError> {
        crate::framed::decode(bytes, PART_MAGIC, PART_VERSION, name, "part")
    }
}

/// What a part carries beyond its tile, for its horizons (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beyond {
    /// Width of the halo around the tile's vertices (m).
    pub halo: f64,
    /// Side of the far field's finest squares (m).
    pub far_block: f64,
    /// Squares grow with distance to span at most about `1 / far_ratio` radian ([`crate::far_field`]); 0 keeps
    /// them at `far_block`.
    pub far_ratio: usize,
}

/// Cuts `tin` into tiles of `tile` metres (see the module docs): `(tile row, tile column, part)` for every tile
/// that holds a triangle, row by row from the north. Without `beyond` (a plan without regions, whose tiles compute
/// no horizons) the parts carry no halo and no far field.
pub fn mesh_parts(tin: &Tin, tile: f64, beyond: Option<Beyond>) -> Vec<(usize, usize, MeshPart)> {
    let b = tin.bbox();
    let cell = |v: f64, lo: f64, k: usize| (((v - lo) / tile).floor().max(0.0) as usize).min(k - 1);
    let kc = ((b.max.x - b.min.x) / tile).ceil().max(1.0) as usize;
    let kr = ((b.max.y - b.min.y) / tile).ceil().max(1.0) as usize;
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); kr * kc];
    for (t, tri) in tin.triangles().iter().enumerate() {
        let c = tri.iter().map(|&v| tin.position(v)).sum::<glam::DVec3>() / 3.0;
        let (r, col) = (cell(b.max.y - c.y, 0.0, kr), cell(c.x, b.min.x, kc));
        members[r * kc + col].push(t as u32);
    }
    // The vertices by the same squares, for the halo's look-up (by vertex index within each square).
    let square_of = |p: glam::DVec3| cell(b.max.y - p.y, 0.0, kr) * kc + cell(p.x, b.min.x, kc);
    let mut by_square: Vec<Vec<u32>> = vec![Vec::new(); if beyond.is_some() { kr * kc } else { 0 }];
    if beyond.is_some() {
        for v in 0..tin.num_vertices() as u32 {
            by_square[square_of(tin.position(v))].push(v);
        }
    }
    // The far field: per square of `far_block` metres, its lowest vertex (the first in vertex order on ties), and
    // the min-pyramid of these squares.
    let z = |v: u32| tin.position(v).z;
    let lower = |a: &u32, b: &u32| (z(*a), *a) < (z(*b), *b);
    let pyramid = beyond.map(|Beyond { far_block, .. }| {
        let fc = ((b.max.x - b.min.x) / far_block).ceil().max(1.0) as usize;
        let fr = ((b.max.y - b.min.y) / far_block).ceil().max(1.0) as usize;
        let fcell = |v: f64, lo: f64, k: usize| (((v - lo) / far_block).floor().max(0.0) as usize).min(k - 1);
        let mut lowest: Vec<Option<u32>> = vec![None; fr * fc];
        for v in 0..tin.num_vertices() as u32 {
            let p = tin.position(v);
            let slot = &mut lowest[fcell(b.max.y - p.y, 0.0, fr) * fc + fcell(p.x, b.min.x, fc)];
            if slot.is_none_or(|w| lower(&v, &w)) {
                *slot = Some(v);
            }
        }
        MinPyramid::new(fr, fc, lowest, lower)
    });

    let mut local = vec![u32::MAX; tin.num_vertices()];
    let mut out = Vec::new();
    for (k, tris) in members.iter().enumerate() {
        if tris.is_empty() {
            continue;
        }
        let mut vertices: Vec<u32> = tris.iter().flat_map(|&t| tin.triangles()[t as usize]).collect();
        vertices.sort_unstable();
        vertices.dedup();
        for (i, &v) in vertices.iter().enumerate() {
            local[v as usize] = i as u32;
        }
        let mut part = MeshPart {
            positions: vertices.iter().map(|&v| tin.position(v).to_array()).collect(),
            triangles: tris
                .iter()
                .map(|&t| tin.triangles()[t as usize].map(|v| local[v as usize]))
                .collect(),
            halo: Vec::new(),
            far: Vec::new(),
        };
        if let (Some(beyond), Some(pyramid)) = (beyond, &pyramid) {
            let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
            for &v in &vertices {
                lo = lo.min(tin.position(v).truncate());
                hi = hi.max(tin.position(v).truncate());
            }
            let tile_box = (lo, hi);
            let (lo, hi) = (lo - beyond.halo, hi + beyond.halo);
            let near = |p: glam::DVec3| p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y;
            // The squares that meet the halo's box (`cell` is monotone, so they hold every vertex in it).
            let mut halo = Vec::new();
            for r in cell(b.max.y - hi.y, 0.0, kr)..=cell(b.max.y - lo.y, 0.0, kr) {
                for c in cell(lo.x, b.min.x, kc)..=cell(hi.x, b.min.x, kc) {
                    let square = &by_square[r * kc + c];
                    halo.extend(
                        square
                            .iter()
                            .filter(|&&v| local[v as usize] == u32::MAX && near(tin.position(v))),
                    );
                }
            }
            halo.sort_unstable();
            part.halo = halo.iter().map(|&v| tin.position(v).to_array()).collect();
            part.far = far_vertices(
                pyramid,
                beyond.far_block,
                (b.min.x, b.max.y),
                tile_box,
                (lo, hi),
                beyond.far_ratio,
            )
            .into_iter()
            .filter(|&v| local[v as usize] == u32::MAX && !near(tin.position(v)))
            .map(|v| tin.position(v).to_array())
            .collect();
        }
        for &v in &vertices {
            local[v as usize] = u32::MAX;
        }
        out.push((k / kc, k % kc, part));
    }
    out
}

/// A mesh tile's far field: the cut through the pyramid of squares of `far_block` metres (their grid's north-west
/// corner at `corner`) that [`crate::far_field`] describes, for the tile whose vertices span `tile` and whose halo
/// spans `window` (x,y boxes). Level-0 squares meeting the window are taken too, for the caller to filter vertex by
/// vertex.
fn far_vertices(
    pyramid: &MinPyramid<u32>,
    far_block: f64,
    corner: (f64, f64),
    tile: (glam::DVec2, glam::DVec2),
    window: (glam::DVec2, glam::DVec2),
    ratio: usize,
) -> Vec<u32> {
    let Some(level0) = pyramid.levels.first() else {
        return Vec::new();
    };
    let (rows, cols) = (level0.rows, level0.cols);
    pyramid.select(|level, r, c| {
        let cells = 1usize << level;
        let side = far_block * cells as f64;
        let (r1, c1) = (((r + 1) * cells).min(rows), ((c + 1) * cells).min(cols));
        let lo = glam::DVec2::new(
            corner.0 + (c * cells) as f64 * far_block,
            corner.1 - r1 as f64 * far_block,
        );
        let hi = glam::DVec2::new(
            corner.0 + c1 as f64 * far_block,
            corner.1 - (r * cells) as f64 * far_block,
        );
        let meets = lo.x <= window.1.x && window.0.x <= hi.x && lo.y <= window.1.y && window.0.y <= hi.y;
        if meets {
            return if level == 0 { Choice::Take } else { Choice::Split };
        }
        let gap = (tile.0 - hi).max(lo - tile.1).max(glam::DVec2::ZERO).max_element();
        if level == 0 || (ratio > 0 && side * ratio as f64 <= gap) {
            Choice::Take
        } else {
            Choice::Split
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The halo looked up square by square is every vertex of the mesh outside the tile and within `halo` of its
    /// vertices' bounding box, in vertex order, whatever the halo's width against the tile's.
    #[test]
    fn the_halo_is_every_other_vertex_near_the_tile() {
        let tin = tin::synth_tin(&tin::SynthOptions::new(1500, 4)).expect("synth");
        let side = tin.bbox().size().x;
        for (per_side, halo) in [(3.0, side / 20.0), (5.0, side / 3.0), (1.5, 0.0), (4.0, 2.0 * side)] {
            let beyond = Beyond {
                halo,
                far_block: side / 10.0,
                far_ratio: 2,
            };
            let parts = mesh_parts(&tin, side / per_side, Some(beyond));
            assert!(parts.len() > 1);
            for (_, _, part) in &parts {
                let bits = |p: &[f64; 3]| p.map(f64::to_bits);
                let own: std::collections::HashSet<[u64; 3]> = part.positions.iter().map(bits).collect();
                let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
                for p in &part.positions {
                    for k in 0..2 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                let near = |p: &[f64; 3]| (0..2).all(|k| p[k] >= lo[k] - halo && p[k] <= hi[k] + halo);
                let expect: Vec<[f64; 3]> = tin
                    .positions()
                    .iter()
                    .map(|p| p.to_array())
                    .filter(|p| !own.contains(&bits(p)) && near(p))
                    .collect();
                assert_eq!(part.halo, expect, "tiles of 1/{per_side}, halo {halo}");
            }
        }
    }
}
