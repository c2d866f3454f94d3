//! Joining the tiles' partial hierarchies into one hierarchy over the whole terrain.
//!
//! - **Mesh.** Vertices are merged by exact x,y (shared side vertices are bit-identical, [`crate::job`]; only a
//!   tile's boundary vertices are looked up, as only they can be shared); two tiles with a vertex at the same x,y but
//!   not the same z were built from different terrains (the DEM changed between their jobs) and are refused, as the
//!   joined mesh would have a crack there;
//!   the tiles' grouped triangles come first, tile after tile in Morton order of the tile grid, then every tile's
//!   always-visible triangles. The joined mesh is checked to be edge-manifold ([`tin::Tin`]) and to have no crack
//!   ([`tin::find_cracks`]: a tile's side vertex on its neighbour's edge at another height, as tiles built from plans
//!   with other `--max-error`s would join).
//! - **Nodes.** Every tile's nodes keep their children, levels and regions, re-expressed relative to the merged
//!   origin with [`cull::StoredRegion::from_f64`] (which only shrinks a region) and circles that only grow. Each
//!   tile becomes one node whose children are the tile's roots, and tiles are joined 2 × 2 up a quadtree of the tile
//!   grid to one root: a tile is a node near the top. Tile and quadtree nodes store no region (never hidden by the
//!   region test; the safe culler tests their bounds like any node), so they add no claim of occlusion.
//!
//! Each tile read is first checked to be its plan's tile ([`Plan::check_built_tile`]: a DEM tile's vertices lie
//! within its samples; a mesh tile has its part's counts and lies within its part's bounding box).
//!
//! [`merge_with`] reads the tiles one at a time and keeps only their nodes, so the merge holds the merged hierarchy
//! and one tile's mesh.

use std::collections::HashMap;

use cull::{BuildInfo, Hierarchy, Mesh, Node, StoredRegion};
use glam::{DVec2, DVec3};
use tin::{Circle, Tin};

use crate::TilesError;
use crate::plan::Plan;

/// A circle in world coordinates.
#[derive(Clone, Copy)]
struct WorldCircle {
    centre: DVec2,
    radius: f64,
}

/// Rounds a world circle to f32 relative to `origin` so that it still encloses the original one.
fn stored(c: WorldCircle, origin: DVec3) -> ([f32; 2], f32) {
    pipeline::stored_circle(
        &Circle {
            centre: c.centre,
            radius: c.radius,
        },
        origin.to_array(),
    )
}

/// A node circle of a tile, in world coordinates, grown by the rounding of the sum.
fn world_circle(n: &Node, origin: DVec3) -> WorldCircle {
    let centre = origin.truncate() + DVec2::new(f64::from(n.centre[0]), f64::from(n.centre[1]));
    let slack = 2.0 * f64::EPSILON * centre.abs().max_element();
    WorldCircle {
        centre,
        radius: f64::from(n.radius) + slack,
    }
}

/// A circle enclosing all of `circles`.
fn enclosing(circles: &[WorldCircle]) -> WorldCircle {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for c in circles {
        lo = lo.min(c.centre - c.radius);
        hi = hi.max(c.centre + c.radius);
    }
    let centre = (lo + hi) * 0.5;
    let radius = circles
        .iter()
        .map(|c| c.centre.distance(centre) + c.radius)
        .fold(0.0, f64::max);
    WorldCircle {
        centre,
        radius: radius * (1.0 + 4.0 * f64::EPSILON),
    }
}

/// Re-expresses a stored region relative to `to` instead of `from` (it can only shrink).
fn move_region(r: &StoredRegion, sectors: u32, from: DVec3, to: DVec3) -> Option<StoredRegion> {
    let points: Vec<[f64; 2]> = r.points.iter().map(|p| [f64::from(p[0]), f64::from(p[1])]).collect();
    let dir = DVec2::from_array(cull::sector_direction(sectors, u32::from(r.sector)));
    let origin_t = dir.dot(to.truncate() - from.truncate());
    StoredRegion::from_f64(r.sector, &points, f64::from(r.tail_slope), origin_t, to.z - from.z)
}

/// Interleaves the bits of a tile's row and column (row bits higher): the order of the tile quadtree's leaves.
fn morton(row: usize, col: usize) -> u64 {
    let mut key = 0u64;
    for b in 0..32 {
        key |= (((row >> b) & 1) as u64) << (2 * b + 1) | (((col >> b) & 1) as u64) << (2 * b);
    }
    key
}

/// Merges the tiles' hierarchies (`tiles[i]` is tile `i` of `plan`) into one (see the module docs).
pub fn merge(plan: &Plan, tiles: &[Hierarchy]) -> Result<Hierarchy, TilesError> {
    if tiles.len() != plan.tiles.len() {
        return Err(TilesError::Parameter(format!(
            "{} tile hierarchies for a plan of {} tiles",
            tiles.len(),
            plan.tiles.len()
        )));
    }
    merge_with(plan, |i| Ok(tiles[i].clone()))
}

/// A tile's nodes, kept while the other tiles are read: re-expressed once the merged origin is known.
struct TileNodes {
    tile: usize,
    nodes: Vec<Node>,
    roots: Vec<u32>,
    origin: DVec3,
    tri_base: u32,
}

/// Where a tile's vertices, grouped triangles and orphans begin in the merged mesh's lists, before the orphans are
/// appended to the grouped triangles (a shared vertex is the first tile's that added it).
struct TileStarts {
    tile: usize,
    vertex: usize,
    triangle: usize,
    orphan: usize,
}

/// Merges the tiles' hierarchies into one (see the module docs), reading them one at a time with `load(i)` (tile `i`
/// of `plan`), in Morton order of the tile grid, each dropped before the next is read: memory is the merged
/// hierarchy and one tile's mesh, not every tile's as well.
pub fn merge_with(
    plan: &Plan,
    mut load: impl FnMut(usize) -> Result<Hierarchy, TilesError>,
) -> Result<Hierarchy, TilesError> {
    let sectors = plan.options.params.sectors;
    let mut order: Vec<usize> = (0..plan.tiles.len()).collect();
    order.sort_by_key(|&i| morton(plan.tiles[i].tile_row, plan.tiles[i].tile_col));

    // The mesh: vertices merged by exact x,y, grouped triangles tile by tile, then all orphans.
    let mut positions: Vec<DVec3> = Vec::new();
    let mut index: HashMap<[u64; 2], (u32, usize)> = HashMap::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut orphans: Vec<[u32; 3]> = Vec::new();
    let mut kept: Vec<TileNodes> = Vec::with_capacity(order.len());
    // Where each tile's vertices, grouped triangles and orphans begin (in the order merged), to name a tile by them.
    let mut starts: Vec<TileStarts> = Vec::with_capacity(order.len());
    let mut build: Option<BuildInfo> = None;
    let mut seeds = 0;
    for &i in &order {
        let mut t = load(i)?;
        plan.check_built_tile(i, &t)?;
        if t.sectors != sectors {
            return Err(TilesError::Parameter(format!(
                "tile {i} has {} sectors, the plan {sectors}",
                t.sectors
            )));
        }
        // Only a vertex on the tile's boundary can be another tile's too: the others are added as they are.
        let shared = boundary_vertices(&t.mesh.triangles, t.mesh.positions.len());
        starts.push(TileStarts {
            tile: i,
            vertex: positions.len(),
            triangle: triangles.len(),
            orphan: orphans.len(),
        });
        let mut remap: Vec<u32> = Vec::with_capacity(t.mesh.positions.len());
        for (p, shared) in t.mesh.positions.iter().zip(shared) {
            let mut add = || {
                positions.push(DVec3::from_array(*p));
                (positions.len() - 1) as u32
            };
            if !shared {
                remap.push(add());
                continue;
            }
            // Shared vertices are joined by x,y; neighbours built from the same samples agree on z to the bit.
            let (v, first) = *index
                .entry([p[0].to_bits(), p[1].to_bits()])
                .or_insert_with(|| (add(), i));
            let z = positions[v as usize].z;
            if z.to_bits() != p[2].to_bits() {
                return Err(TilesError::Parameter(format!(
                    "tiles {first} and {i} ({}) disagree on the terrain's height at x {}, y {} ({z} and {}): they \
                     were not built from the same terrain (the DEM changed between their builds?); plan and build \
                     them again",
                    plan.tiles[i].output.display(),
                    p[0],
                    p[1],
                    p[2]
                )));
            }
            remap.push(v);
        }
        let tri_base = triangles.len() as u32;
        let [a, b] = t.always_visible;
        let moved = |tri: &[u32; 3]| tri.map(|v| remap[v as usize]);
        triangles.extend(t.mesh.triangles[..a as usize].iter().map(moved));
        orphans.extend(t.mesh.triangles[a as usize..b as usize].iter().map(moved));
        seeds = t.build.seeds.saturating_add(seeds);
        build.get_or_insert_with(|| t.build.clone());
        kept.push(TileNodes {
            tile: i,
            nodes: std::mem::take(&mut t.nodes),
            roots: std::mem::take(&mut t.roots),
            origin: DVec3::from_array(t.origin),
            tri_base,
        });
    }
    drop(index);
    let grouped = triangles.len() as u32;
    triangles.append(&mut orphans);
    drop(orphans);
    let tin = Tin::from_parts(positions, triangles).map_err(|e| {
        TilesError::Parameter(format!(
            "the tiles do not join into one terrain (plan and build them again): {e}"
        ))
    })?;
    // A vertex of one tile on a side edge of its neighbour at another height (a T-junction: the tiles were built
    // from different plans, say with other `--max-error`s): the surface would have a crack there, which no culler's
    // proof allows. Such a vertex and such an edge both lie on the joined mesh's border (the edge has its one
    // triangle in its tile, the vertex's side edges theirs in the other), so only the triangles with a border edge
    // are searched: every crack between tiles is among theirs, and one found among them is one of the whole mesh.
    let (border_ids, border): (Vec<usize>, Vec<[u32; 3]>) = tin
        .triangles()
        .iter()
        .zip(tin.neighbours())
        .enumerate()
        .filter(|(_, (_, n))| n.contains(&tin::NO_NEIGHBOUR))
        .map(|(k, (t, _))| (k, *t))
        .unzip();
    let cracks = tin::find_cracks(tin.positions(), &border, 1);
    if let Some(&[v, t]) = cracks.first.first() {
        let point = |v: u32| {
            let p = tin.position(v);
            format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
        };
        let corners = border[t as usize].map(point);
        // The tile that added a vertex or a triangle: the last whose start is not past it.
        let tile_of = |start: fn(&TileStarts) -> usize, k: usize| {
            let i = starts[starts.partition_point(|s| start(s) <= k) - 1].tile;
            format!("tile {i}, {}", plan.tiles[i].output.display())
        };
        let k = border_ids[t as usize];
        let triangle_tile = if k < grouped as usize {
            tile_of(|s| s.triangle, k)
        } else {
            tile_of(|s| s.orphan, k - grouped as usize)
        };
        return Err(TilesError::Parameter(format!(
            "the tiles do not join into one terrain (plan and build them again): {} vertices lie on an edge of a \
             neighbouring tile's triangle at another height than the edge's (a crack), the first at {} ({}) on the \
             triangle {} ({triangle_tile}); were the tiles built from this plan?",
            cracks.count,
            point(v),
            tile_of(|s| s.vertex, v as usize),
            corners.join(", ")
        )));
    }
    drop(border);
    let origin = tin.origin();

    // The tiles' nodes, then one node per tile.
    let mut nodes: Vec<Node> = Vec::new();
    let mut circles: Vec<WorldCircle> = Vec::new();
    let mut tile_node: HashMap<(usize, usize), u32> = HashMap::new();
    for t in kept {
        let base = nodes.len() as u32;
        for n in t.nodes {
            let c = world_circle(&n, t.origin);
            let (centre, radius) = stored(c, origin);
            circles.push(c);
            nodes.push(Node {
                centre,
                radius,
                children: n.children.iter().map(|&k| k + base).collect(),
                triangles: n.triangles.map(|k| k + t.tri_base),
                level: n.level,
                regions: n
                    .regions
                    .iter()
                    .filter_map(|r| move_region(r, sectors, t.origin, origin))
                    .collect(),
            });
        }
        let mut roots: Vec<u32> = t.roots.iter().map(|&r| r + base).collect();
        if roots.is_empty() {
            continue;
        }
        roots.sort_by_key(|&r| nodes[r as usize].triangles[0]);
        let id = push_parent(&mut nodes, &mut circles, roots, origin);
        tile_node.insert((plan.tiles[t.tile].tile_row, plan.tiles[t.tile].tile_col), id);
    }

    // The quadtree of tiles.
    let (rows, cols) = plan
        .tiles
        .iter()
        .fold((0, 0), |(r, c), t| (r.max(t.tile_row + 1), c.max(t.tile_col + 1)));
    let mut side = 1;
    while side < rows.max(cols) {
        side *= 2;
    }
    let mut level_nodes: HashMap<(usize, usize), u32> = tile_node;
    while side > 1 {
        let mut up: HashMap<(usize, usize), u32> = HashMap::new();
        let mut keys: Vec<(usize, usize)> = level_nodes.keys().map(|&(r, c)| (r / 2, c / 2)).collect();
        keys.sort_unstable();
        keys.dedup();
        for (r, c) in keys {
            let children: Vec<u32> = [(0, 0), (0, 1), (1, 0), (1, 1)]
                .iter()
                .filter_map(|&(dr, dc)| level_nodes.get(&(2 * r + dr, 2 * c + dc)).copied())
                .collect();
            let id = if children.len() == 1 {
                children[0]
            } else {
                push_parent(&mut nodes, &mut circles, children, origin)
            };
            up.insert((r, c), id);
        }
        level_nodes = up;
        side /= 2;
    }
    let roots: Vec<u32> = level_nodes.values().copied().collect();

    let (positions, triangles) = tin.into_parts();
    let h = Hierarchy {
        sectors,
        origin: origin.to_array(),
        nodes,
        roots,
        always_visible: [grouped, triangles.len() as u32],
        mesh: Mesh {
            positions: positions.iter().map(|p| p.to_array()).collect(),
            triangles,
        },
        build: BuildInfo {
            seeds,
            ..build.ok_or_else(|| TilesError::Parameter("a plan without tiles".into()))?
        },
    };
    h.check_invariants()
        .map_err(|e| TilesError::Parameter(format!("the merged hierarchy is malformed: {e}")))?;
    Ok(h)
}

/// Which of a mesh's `n` vertices lie on its boundary: on an edge of only one of its triangles. A vertex that another
/// tile shares has a triangle around it outside this tile, so it is one of them (a vertex all of whose triangles are
/// in the tile is inside it).
fn boundary_vertices(triangles: &[[u32; 3]], n: usize) -> Vec<bool> {
    let mut edges: Vec<u64> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (u64::from(a.min(b)) << 32) | u64::from(a.max(b)))
        .collect();
    edges.sort_unstable();
    let mut on = vec![false; n];
    for run in edges.chunk_by(|a, b| a == b) {
        if let [e] = run {
            for v in [e >> 32, e & u64::from(u32::MAX)] {
                if let Some(flag) = on.get_mut(v as usize) {
                    *flag = true;
                }
            }
        }
    }
    on
}

/// Appends a region-less node over `children` (whose ranges are consecutive, in order) and returns its index.
fn push_parent(nodes: &mut Vec<Node>, circles: &mut Vec<WorldCircle>, children: Vec<u32>, origin: DVec3) -> u32 {
    let c = enclosing(&children.iter().map(|&k| circles[k as usize]).collect::<Vec<_>>());
    let (centre, radius) = stored(c, origin);
    let first = nodes[children[0] as usize].triangles[0];
    let last = nodes[children[children.len() - 1] as usize].triangles[1];
    let level = children.iter().map(|&k| nodes[k as usize].level).max().unwrap_or(0) + 1;
    nodes.push(Node {
        centre,
        radius,
        children,
        triangles: [first, last],
        level,
        regions: Vec::new(),
    });
    circles.push(c);
    (nodes.len() - 1) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_orders_quadrants() {
        let keys: Vec<u64> = [(0, 0), (0, 1), (1, 0), (1, 1), (0, 2)]
            .iter()
            .map(|&(r, c)| morton(r, c))
            .collect();
        assert_eq!(keys, vec![0, 1, 2, 3, 4]);
    }

    #[test]
    fn enclosing_circle_contains_its_circles() {
        let cs = [
            WorldCircle {
                centre: DVec2::new(0.0, 0.0),
                radius: 1.0,
            },
            WorldCircle {
                centre: DVec2::new(10.0, 3.0),
                radius: 2.5,
            },
            WorldCircle {
                centre: DVec2::new(4.0, -7.0),
                radius: 0.5,
            },
        ];
        let e = enclosing(&cs);
        for c in cs {
            assert!(c.centre.distance(e.centre) + c.radius <= e.radius);
        }
    }
}
