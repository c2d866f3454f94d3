//! The bodies of the fuzz targets: each takes arbitrary bytes and must never panic (errors are fine).
//!
//! - `obj_import`: [`tin::parse_obj`] in both modes (re-triangulate, keep faces) and both duplicate policies (the
//!   second with y up).
//! - `dem_readers`: the `.npy`, `.asc`, `.hgt`, `.png` and GeoTIFF parsers of `tin::dem`.
//! - `geotiff`: [`tin::dem::geotiff::parse_geotiff`] alone (TIFF structure, GeoKeys, decompression, predictors),
//!   with no band and with band 2 chosen; a grid that loads is simplified a little.
//! - `tch_load`: [`cull::Hierarchy::from_bytes`]; a file that loads is culled from a few cameras, degenerate ones
//!   included (inside a node, far away, non-finite).
//! - `tile_files`: what a tiled build's jobs read: a plan ([`tiles::Plan::parse`]), a mesh tile's part
//!   ([`tiles::part::MeshPart::from_bytes`]) and a DEM tile's far field ([`tiles::far_field::far_from_bytes`]), the
//!   framed ones also resealed; a part that decodes is made into its tile's TIN and triangulated with its halo and
//!   far points, as its job does.

use std::path::Path;

use cull::{AnyCuller, Camera, CullMethod, Hierarchy};
use tin::dem::hgt::TileName;
use tin::{DedupePolicy, DemOptions, ObjImportOptions, UpAxis};

/// Inputs larger than this are cut (keeps each run fast; the parsers' limits are tested elsewhere).
pub const MAX_INPUT: usize = 1 << 20;

/// `tin::parse_obj` on `data`, every option combination.
pub fn obj_import(data: &[u8]) {
    let data = &data[..data.len().min(MAX_INPUT)];
    for keep_faces in [false, true] {
        for (dedupe, up) in [
            (DedupePolicy::Reject, UpAxis::Z),
            (DedupePolicy::KeepHighest, UpAxis::Y),
        ] {
            let opts = ObjImportOptions { keep_faces, dedupe, up };
            if let Ok((tin, _)) = tin::parse_obj(data, "fuzz.obj", &opts) {
                // A TIN that loads is a valid height field: its basic queries must hold up.
                let _ = tin.bbox();
                for t in 0..tin.num_triangles().min(64) {
                    let _ = tin.triangle_area_3d(t);
                }
            }
        }
    }
}

/// The five DEM parsers on `data` (GeoTIFF also with band 2 chosen).
pub fn dem_readers(data: &[u8]) {
    let data = &data[..data.len().min(MAX_INPUT)];
    let _ = tin::dem::npy::parse_npy(data, Path::new("fuzz.npy"));
    let opts = DemOptions::default();
    let _ = tin::dem::asc::parse_asc(data, Path::new("fuzz.asc"), &opts);
    let tile = TileName { lat: 43, lon: -123 };
    let _ = tin::dem::hgt::parse_hgt(data, tile, Path::new("N43W123.hgt"), &opts);
    let png_opts = DemOptions {
        spacing: Some((10.0, 10.0)),
        z_scale: 1.0,
        band: None,
    };
    if let Ok(grid) = tin::dem::png::parse_png(data, Path::new("fuzz.png"), &png_opts) {
        let _ = grid.points();
    }
    let _ = tin::dem::geotiff::parse_geotiff(data, Path::new("fuzz.tif"), &opts);
}

/// The GeoTIFF parser on `data`, with no band and with band 2 chosen.
pub fn geotiff(data: &[u8]) {
    let data = &data[..data.len().min(MAX_INPUT)];
    for band in [None, Some(2)] {
        let opts = DemOptions {
            band,
            ..DemOptions::default()
        };
        if let Ok((grid, _)) = tin::dem::geotiff::parse_geotiff(data, Path::new("fuzz.tif"), &opts)
            && grid.rows * grid.cols <= 4096
        {
            let simplify = tin::SimplifyOptions {
                max_vertices: Some(16),
                max_error: None,
            };
            let _ = tin::simplify(&grid, &simplify, None);
        }
    }
}

/// `Hierarchy::from_bytes` on `data`, then a few culls when it loads. A mutated file almost never passes the
/// checksum, so `data` is also tried with its header resealed (payload length and CRC-32 recomputed): that sends
/// the mutations on to the decoder and the invariant checks.
pub fn tch_load(data: &[u8]) {
    let data = &data[..data.len().min(MAX_INPUT)];
    if let Ok(h) = Hierarchy::from_bytes(data) {
        cull_some(&h);
    }
    if let Some(sealed) = reseal(data)
        && let Ok(h) = Hierarchy::from_bytes(&sealed)
    {
        cull_some(&h);
    }
}

/// `data` with the `.tch` header's length and checksum fields made to match the payload (bytes 24 onwards).
pub fn reseal(data: &[u8]) -> Option<Vec<u8>> {
    const HEADER: usize = 24;
    if data.len() < HEADER {
        return None;
    }
    let payload = &data[HEADER..];
    let mut out = data.to_vec();
    out[12..20].copy_from_slice(&(payload.len() as u64).to_le_bytes());
    out[20..24].copy_from_slice(&crc32fast::hash(payload).to_le_bytes());
    Some(out)
}

/// Culls `h` by every method from degenerate and ordinary cameras (and from a hair beside its first vertices, where a
/// vertex lies almost exactly beside the camera), checking the draw list's ranges.
fn cull_some(h: &Hierarchy) {
    let mut cameras = vec![
        Camera::all_around(h.origin),
        Camera::all_around([h.origin[0] + 1e7, h.origin[1] - 1e7, h.origin[2] + 5.0]),
        Camera::all_around([0.0, 0.0, 500.0]),
        Camera::all_around([0.0, 0.0, 5000.0]),
        Camera::all_around([f64::NAN, 0.0, 0.0]),
        Camera::all_around([f64::INFINITY, f64::NEG_INFINITY, 1.0]),
        Camera {
            position: h.origin,
            yaw: 1.0,
            hfov: 0.5,
        },
        Camera {
            position: h.origin,
            yaw: f64::NAN,
            hfov: -1.0,
        },
    ];
    for n in h.nodes.iter().take(4) {
        let p = [
            h.origin[0] + f64::from(n.centre[0]),
            h.origin[1] + f64::from(n.centre[1]),
            h.origin[2] + 2.0,
        ];
        cameras.push(Camera::all_around(p));
        cameras.push(Camera::all_around([
            p[0] + 3.0 * f64::from(n.radius),
            p[1],
            p[2] - 50.0,
        ]));
    }
    let hair = |x: f64| f64::from_bits(x.to_bits() ^ 1);
    for v in h.mesh.positions.iter().take(3) {
        let p = [0, 1, 2].map(|k| h.origin[k] + v[k]);
        cameras.push(Camera::all_around([hair(p[0]), p[1] + 7.0, p[2] + 1.0]));
        cameras.push(Camera::all_around([p[0] + 7.0, hair(p[1]), p[2] + 1.0]));
    }
    let total = h.num_triangles();
    for method in CullMethod::ALL {
        cull_all(&AnyCuller::new(h, method), &cameras, total);
    }
}

/// Culls from every camera, checking that each draw list stays within the `total` triangles.
fn cull_all(culler: &AnyCuller, cameras: &[Camera], total: usize) {
    for c in cameras {
        let list = culler.cull(c);
        let mask = list.mask(total);
        assert_eq!(mask.len(), total, "a draw mask has one flag per triangle");
        for r in &list.ranges {
            assert!(
                r[0] <= r[1] && r[1] as usize <= total,
                "draw range {r:?} out of 0..{total}"
            );
        }
    }
}

/// A tiled build's job inputs on `data` (see the module docs): a plan, a mesh tile's part (its TIN and the sweep's
/// points built when it decodes) and a DEM tile's far field, the framed files also with their header resealed.
pub fn tile_files(data: &[u8]) {
    let data = &data[..data.len().min(MAX_INPUT)];
    let name = Path::new("fuzz.bin");
    let _ = tiles::Plan::parse(data.to_vec(), Path::new("fuzz.json"));
    for bytes in std::iter::once(data.to_vec()).chain(reseal(data)) {
        if let Ok(part) = tiles::part::MeshPart::from_bytes(&bytes, name)
            && part.positions.len() + part.halo.len() + part.far.len() <= 4096
        {
            let to_points = |v: &[[f64; 3]]| v.iter().map(|p| glam::DVec3::from_array(*p)).collect::<Vec<_>>();
            if tin::Tin::from_parts(to_points(&part.positions), part.triangles.clone()).is_ok() {
                let mut points = to_points(&part.positions);
                points.extend(to_points(&part.halo));
                points.extend(to_points(&part.far));
                let _ = tin::triangulate(&points, DedupePolicy::Reject);
            }
        }
        let _ = tiles::far_field::far_from_bytes(&bytes, [1201, 1201], name);
    }
}
