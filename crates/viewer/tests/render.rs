//! Headless renders of a tiny hand-made hierarchy: colours at known pixels, orphans grey, culled groups as
//! wireframe, the GPU drawing exactly the culler's triangles, and the culled/unculled comparison.
//!
//! Without any GPU adapter these tests print a SKIP notice and pass, unless `TINCULL_REQUIRE_GPU` is set.

mod common;

use common::{close, gpu, shaded, tiny_hierarchy, world};
use cull::{Camera, Culler};
use glam::{Vec3, Vec4};
use proptest::prelude::*;
use viewer::camera::{MapView, Orbit};
use viewer::palette::{self, ORPHAN_COLOUR, group_colour};
use viewer::render::{DrawItem, DrawStyle, Frame, Renderer};
use viewer::{ColourMode, GpuScene, RenderOptions, Terrain, ViewKind};

const SIZE: [u32; 2] = [256, 256];

fn terrain() -> Terrain {
    Terrain::from_hierarchy(tiny_hierarchy()).expect("valid fixture")
}

/// Pixel of a local point under a clip transform.
fn project(view_proj: glam::Mat4, p: Vec3, size: [u32; 2]) -> (u32, u32) {
    let c: Vec4 = view_proj * p.extend(1.0);
    let ndc = c.truncate() / c.w;
    let x = (ndc.x + 1.0) * 0.5 * size[0] as f32;
    let y = (1.0 - ndc.y) * 0.5 * size[1] as f32;
    (x as u32, y as u32)
}

#[test]
fn map_shows_each_group_in_its_colour_and_orphans_grey() {
    let Some(gpu) = gpu() else { return };
    let t = terrain();
    let out = viewer::render(
        gpu,
        &t,
        &RenderOptions {
            view: ViewKind::Map,
            size: SIZE,
            ..Default::default()
        },
    )
    .unwrap();
    let map = MapView::fit(t.min, t.max, 1.0);
    let px = |x: f32, y: f32| {
        let p = map.local_to_pixel(glam::Vec2::new(x, y), SIZE[0] as f32, SIZE[1] as f32);
        out.image.pixel(p.x as u32, p.y as u32).unwrap()
    };
    // Quadrant centres (local): A south-west, B south-east, C north-west, orphans north-east.
    let expect = [
        ((25.0, 25.0), shaded(group_colour(0))),
        ((75.0, 25.0), shaded(group_colour(1))),
        ((25.0, 75.0), shaded(group_colour(2))),
        ((75.0, 75.0), shaded(ORPHAN_COLOUR)),
    ];
    for ((x, y), colour) in expect {
        let got = px(x, y);
        assert!(close(got, colour, 3), "at ({x}, {y}): got {got:?}, expected {colour:?}");
    }
    let grey = shaded(ORPHAN_COLOUR);
    assert!(
        grey[0] == grey[1] && grey[1] == grey[2] && grey[0] < 80,
        "orphans are dark grey: {grey:?}"
    );
    // Outside the terrain: the background.
    let corner = out.image.pixel(0, 0).unwrap();
    assert_eq!(corner, palette::to_rgba8(palette::BACKGROUND));
    // One draw of every triangle.
    assert_eq!(out.frame.draws, 1);
    assert_eq!(out.frame.triangles, 32);
}

#[test]
fn orbit_draws_culled_groups_as_light_wireframe() {
    let Some(gpu) = gpu() else { return };
    let t = terrain();
    let eye = world(5.0, 5.0, 10.0);
    // The fixture's regions hide B; the thesis' test believes them (the safe culler would not cull B).
    let base = RenderOptions {
        view: ViewKind::Orbit,
        size: SIZE,
        method: cull::CullMethod::Thesis,
        ..Default::default()
    };
    let plain = viewer::render(gpu, &t, &base).unwrap();
    let culled = viewer::render(
        gpu,
        &t,
        &RenderOptions {
            eye: Some(eye),
            ..base.clone()
        },
    )
    .unwrap();
    // The culler hides B only.
    let ranges = culled.ranges.clone().unwrap();
    assert_eq!(ranges, vec![[0, 8], [16, 32]]);
    let orbit = Orbit::overview(t.min, t.max, 1.0, None, None);
    let (bx, by) = project(orbit.view_proj(1.0), Vec3::new(70.0, 22.0, 0.0), SIZE);
    let (ax, ay) = project(orbit.view_proj(1.0), Vec3::new(40.0, 10.0, 0.0), SIZE);
    let solid_b = shaded(group_colour(1));
    let solid_a = shaded(group_colour(0));
    assert!(close(plain.image.pixel(bx, by).unwrap(), solid_b, 3));
    assert!(
        close(culled.image.pixel(ax, ay).unwrap(), solid_a, 3),
        "drawn group A stays solid"
    );
    let inside_b = culled.image.pixel(bx, by).unwrap();
    assert!(
        !close(inside_b, solid_b, 10),
        "culled group B is not solid: {inside_b:?}"
    );
    // B's solid colour is gone from the image, and its lightened wireframe colour is there.
    let near = |img: &viewer::RgbaImage, c: [u8; 4]| {
        img.pixels
            .chunks_exact(4)
            .filter(|p| close([p[0], p[1], p[2], p[3]], c, 3))
            .count()
    };
    assert!(near(&plain.image, solid_b) > 500);
    assert_eq!(near(&culled.image, solid_b), 0);
    let b = group_colour(1);
    let l = f64::from(viewer::render::WIRE_LIGHTEN);
    let light: [f64; 3] = std::array::from_fn(|k| b[k] + (1.0 - b[k]) * l);
    assert!(
        near(&culled.image, palette::to_rgba8(light)) > 20,
        "wireframe of B drawn (unshaded)"
    );
    // The images differ exactly because of B's wireframe and the marker.
    assert_ne!(plain.image, culled.image);
    // Drawn ranges solid and culled ones wire: three indexed draws.
    assert_eq!(culled.frame.draws, 3);
}

#[test]
fn gpu_processes_exactly_the_culled_triangles() {
    let Some(gpu) = gpu() else { return };
    let t = terrain();
    let h = t.hierarchy.clone().unwrap();
    let culler = Culler::new(&h);
    let list = culler.cull(&Camera::all_around(world(5.0, 5.0, 10.0)));
    assert_eq!(list.stats.triangles_drawn, 24);
    let colours = t.colours(ColourMode::Groups, None, None).unwrap();
    let scene = GpuScene::new(gpu, &t, &colours).unwrap();
    let mut renderer = Renderer::new(gpu, SIZE[0], SIZE[1]).unwrap();
    let items = viewer::headless::solid(&list.ranges);
    let stats = renderer
        .render(
            gpu,
            &Frame {
                scene: &scene,
                view_proj: MapView::fit(t.min, t.max, 1.0).view_proj(),
                items: &items,
                marker: None,
                count_primitives: true,
            },
        )
        .unwrap();
    assert_eq!(stats.draws as usize, list.ranges.len());
    assert_eq!(stats.triangles, u64::from(list.stats.triangles_drawn));
    match stats.gpu_primitives {
        Some(p) => {
            assert_eq!(p, u64::from(list.stats.triangles_drawn), "clipper invocations");
            assert_eq!(stats.gpu_vertices, Some(3 * p), "vertex shader invocations");
        }
        None => eprintln!(
            "note: no pipeline-statistics queries on {}; counted draws only",
            gpu.describe()
        ),
    }
}

#[test]
fn compare_shows_a_false_cull_and_none_when_looking_away() {
    let Some(gpu) = gpu() else { return };
    let t = terrain();
    // On flat ground B is plainly visible, so the fixture's "always hidden" B is a false cull when in view.
    let towards = RenderOptions {
        view: ViewKind::Eye,
        eye: Some(world(5.0, 25.0, 30.0)),
        yaw_deg: Some(0.0),
        pitch_deg: Some(-20.0),
        fov_deg: 90.0,
        size: SIZE,
        compare: true,
        timing_runs: 1,
        method: cull::CullMethod::Thesis,
        ..Default::default()
    };
    let out = viewer::render(gpu, &t, &towards).unwrap();
    let c = out.compare.unwrap();
    assert!(
        c.differing_pixels > 100,
        "B in view: {} differing pixels",
        c.differing_pixels
    );
    assert_eq!(c.difference.count([255, 0, 0, 255]), c.differing_pixels);
    assert_eq!(c.unculled_frame.triangles, 32);
    assert_eq!(c.culled_frame.triangles, 24);
    // Looking west, away from B (which lies east): culled and unculled frames are identical.
    let away = RenderOptions {
        yaw_deg: Some(180.0),
        eye: Some(world(60.0, 90.0, 30.0)),
        ..towards
    };
    let out = viewer::render(gpu, &t, &away).unwrap();
    let c = out.compare.unwrap();
    assert_eq!(c.differing_pixels, 0);
    assert_eq!(out.image, c.unculled);
}

#[test]
fn plain_meshes_render_by_height_and_reject_group_colours() {
    let Some(gpu) = gpu() else { return };
    let h = tiny_hierarchy();
    let positions = h
        .mesh
        .positions
        .iter()
        .map(|p| glam::DVec3::new(p[0], p[1], p[2] + p[0] * 0.01))
        .collect();
    let tin = tin::Tin::from_parts(positions, h.mesh.triangles.clone()).unwrap();
    let t = Terrain::from_tin(&tin).unwrap();
    let opts = RenderOptions {
        size: [64, 64],
        ..Default::default()
    };
    let out = viewer::render(gpu, &t, &opts).unwrap();
    assert!(out.cull.is_none());
    let groups = RenderOptions {
        colour: Some(ColourMode::Groups),
        ..opts.clone()
    };
    let err = viewer::render(gpu, &t, &groups).unwrap_err().to_string();
    assert!(err.contains("needs a hierarchy"), "{err}");
    let eye = RenderOptions {
        view: ViewKind::Eye,
        ..opts
    };
    let err = viewer::render(gpu, &t, &eye).unwrap_err().to_string();
    assert!(err.contains("--eye"), "{err}");
}

#[test]
fn split_items_wireframes_exactly_the_complement() {
    let items = viewer::headless::split_items(&[[0, 8], [16, 32]], 40);
    let wire: Vec<[u32; 2]> = items
        .iter()
        .filter(|i| i.style == DrawStyle::Wire)
        .map(|i| i.range)
        .collect();
    assert_eq!(wire, vec![[8, 16], [32, 40]]);
}

fn scene_and_renderer() -> Option<(&'static viewer::Gpu, Terrain, GpuScene, Renderer)> {
    let gpu = gpu()?;
    let t = terrain();
    let colours = t.colours(ColourMode::Groups, None, None).unwrap();
    let scene = GpuScene::new(gpu, &t, &colours).unwrap();
    let renderer = Renderer::new(gpu, 32, 32).unwrap();
    Some((gpu, t, scene, renderer))
}

/// Any set of disjoint ranges, solid or wire, is drawn with one call each and exactly its triangles (a property
/// test run by hand, so that a missing GPU is a skip before any case runs).
#[test]
fn gpu_draws_exactly_the_given_ranges() {
    let Some((gpu, t, scene, renderer)) = scene_and_renderer() else {
        return;
    };
    let renderer = std::cell::RefCell::new(renderer);
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig {
        cases: 24,
        failure_persistence: None,
        ..ProptestConfig::default()
    });
    let strategy = (proptest::collection::btree_set(0u32..=32, 0..10), any::<u16>());
    runner
        .run(&strategy, |(cuts, wire)| {
            let cuts: Vec<u32> = cuts.into_iter().collect();
            let items: Vec<DrawItem> = cuts
                .windows(2)
                .enumerate()
                .map(|(k, w)| DrawItem {
                    range: [w[0], w[1]],
                    style: if wire >> (k % 16) & 1 == 1 {
                        DrawStyle::Wire
                    } else {
                        DrawStyle::Solid
                    },
                })
                .collect();
            let expected: u64 = items.iter().map(|i| u64::from(i.range[1] - i.range[0])).sum();
            let stats = renderer
                .borrow_mut()
                .render(
                    gpu,
                    &Frame {
                        scene: &scene,
                        view_proj: MapView::fit(t.min, t.max, 1.0).view_proj(),
                        items: &items,
                        marker: None,
                        count_primitives: true,
                    },
                )
                .unwrap();
            prop_assert_eq!(stats.triangles, expected);
            prop_assert_eq!(
                stats.draws as usize,
                items.iter().filter(|i| i.range[0] < i.range[1]).count()
            );
            if let Some(p) = stats.gpu_primitives {
                prop_assert_eq!(p, expected);
            }
            Ok(())
        })
        .unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Map pixels and local coordinates convert back and forth.
    #[test]
    fn map_pixels_round_trip(w in 1.0f32..5000.0, h in 1.0f32..5000.0, u in 0.0f32..1.0, v in 0.0f32..1.0, aspect in 0.2f32..5.0) {
        let map = MapView::fit([-w, -h, 0.0], [w * 0.5, h, 10.0], aspect);
        let (pw, ph) = (400.0 * aspect, 400.0);
        let p = map.pixel_to_local(u * pw, v * ph, pw, ph);
        let q = map.local_to_pixel(p, pw, ph);
        prop_assert!((q.x - u * pw).abs() < 0.05 && (q.y - v * ph).abs() < 0.05);
        // The whole footprint is inside the image.
        for corner in [glam::Vec2::new(-w, -h), glam::Vec2::new(w * 0.5, h)] {
            let c = map.local_to_pixel(corner, pw, ph);
            prop_assert!(c.x >= -0.01 && c.x <= pw + 0.01 && c.y >= -0.01 && c.y <= ph + 0.01);
        }
    }

    /// The difference image marks exactly the pixels that differ.
    #[test]
    fn difference_counts_differing_pixels(a in proptest::collection::vec(0u8..3, 64), b in proptest::collection::vec(0u8..3, 64)) {
        let img = |v: &[u8]| viewer::RgbaImage { width: 4, height: 4, pixels: v.to_vec() };
        let (d, n) = img(&a).difference(&img(&b)).unwrap();
        let brute = a.chunks_exact(4).zip(b.chunks_exact(4)).filter(|(x, y)| x != y).count() as u64;
        prop_assert_eq!(n, brute);
        prop_assert_eq!(d.count([255, 0, 0, 255]), brute);
    }
}
