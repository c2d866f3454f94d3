//! Run-time culling cost per viewpoint, per method, on the bundled default terrain.
//!
//! `cargo bench -p eval --bench cull`. Builds `meshes/jacksboro-10k.obj` with default parameters (16 × 4 sectors),
//! draws 20 `ground` and 20 `high` viewpoints (seed 1), and times one cull per viewpoint (cycling over the 40, 360°
//! view) for the safe culler (the default), the thesis' region test over the hierarchy and the per-triangle method; the
//! safe culler also on the ground and the high viewpoints apart. With `TINCULL_BENCH_MESH=path.obj` another mesh is
//! used instead (its build uses 500 seeds when it has more than 50,000 vertices, like the thesis' 100k set).
//!
//! Before timing the safe culler, its draw lists from the 40 viewpoints are checked against ground truth: not one
//! visible triangle may be culled; its mean nodes tested, work units and occluder edges written per view are printed
//! for the ground and the high viewpoints (what its time is spent on).
//!
//! Lloyd & Egbert's culler (`lloyd-egbert`) runs over the default quadtree build of the same mesh (`tincull build
//! --grouping quadtree`), with 256, 1024 and 4096 horizon columns per face (`lloyd-egbert_w256`, …), after the same
//! check against ground truth; its preparation time, occluder count and nodes tested per cull are printed. Both it
//! (`lloyd-egbert_w1024_fov90`) and the safe culler (`safe_w1024_fov90`) are also timed in the paper's setting: a 90°
//! frustum of 1,024 columns (the image's width), turning east, north, west and south over the same viewpoints.
//!
//! Before timing, each culler's draw lists are checked against the straightforward reference culler of the `cull`
//! crate's tests, for 20 viewpoints of every class, with and without a frustum (this also runs under
//! `cargo test -p eval --release --bench cull`), and the number of nodes tested per cull is printed.

#[path = "../../cull/tests/reference/mod.rs"]
mod reference;

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use cull::{Camera, Culler, DrawList, Hierarchy, LloydEgbertCuller, SafeCuller, SafeParams};
use eval::evaluate::{hierarchy_tin, per_triangle_of};
use pipeline::{BuildParams, build};
use truth::{GroundTruth, ViewpointClass, viewpoints};

/// Panics unless `culler` gives the reference's draw list for every camera.
fn check_against_reference(method: &str, h: &Hierarchy, culler: &Culler, cameras: &[Camera]) {
    let reference = reference::ReferenceCuller::new(h);
    let mut out = DrawList::default();
    for (i, camera) in cameras.iter().enumerate() {
        culler.cull_into(camera, &mut out);
        if let Err(e) = reference::compare(&out, &reference.cull(camera)) {
            panic!("{method}: camera {i} ({camera:?}): {e}");
        }
    }
}

fn bench(c: &mut Criterion) {
    let path = std::env::var_os("TINCULL_BENCH_MESH")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../meshes/jacksboro-10k.obj"));
    let (tin, _) = tin::read_obj(&path, &Default::default()).expect("bench mesh");
    let mut params = BuildParams::default();
    if tin.num_vertices() > 50_000 {
        params.crystal.seeds = Some(500);
    }
    let built = build(&tin, &params, None).expect("build");
    let h = built.hierarchy;
    let htin = hierarchy_tin(&h).expect("mesh");
    let per_triangle = per_triangle_of(&h, &htin).expect("per-triangle regions");
    let mut eyes = viewpoints(&htin, ViewpointClass::Ground, 20, 1);
    eyes.extend(viewpoints(&htin, ViewpointClass::High, 20, 1));
    let cameras: Vec<Camera> = eyes.iter().map(|e| Camera::all_around(e.to_array())).collect();
    let mut checks: Vec<Camera> = Vec::new();
    for class in ViewpointClass::ALL {
        for (k, e) in viewpoints(&htin, class, 20, 2).iter().enumerate() {
            checks.push(Camera::all_around(e.to_array()));
            checks.push(Camera {
                position: e.to_array(),
                yaw: k as f64,
                hfov: 1.0 + 0.25 * (k % 8) as f64,
            });
        }
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut group = c.benchmark_group(format!("cull/{name}"));
    let safe = SafeCuller::new(&h, SafeParams::default());
    let truth = GroundTruth::new(&htin);
    let mut list = DrawList::default();
    let mut saved = 0u64;
    // Per class (ground, high): nodes tested, work units and occluder edges written, summed over the views.
    let mut work = [[0u64; 3]; 2];
    for (i, (camera, eye)) in cameras.iter().zip(&eyes).enumerate() {
        safe.cull_into(camera, &mut list);
        let drawn = list.mask(htin.num_triangles());
        let visible = truth.visible_triangles(*eye);
        assert!(
            visible.iter().zip(&drawn).all(|(&v, &d)| d || !v),
            "safe culler: a visible triangle culled from {eye}"
        );
        saved += u64::from(list.stats.triangles_culled);
        let s = list.stats;
        for (sum, n) in work[i / 20].iter_mut().zip([s.nodes_tested, s.work, s.occluder_edges]) {
            *sum += u64::from(n);
        }
    }
    println!(
        "cull/{name}/safe: {} tree nodes; {:.0} triangles culled per view on average, none visible",
        safe.tree_nodes(),
        saved as f64 / cameras.len() as f64
    );
    for (class, [tested, units, edges]) in ["ground", "high"].iter().zip(work) {
        println!(
            "cull/{name}/safe_{class}: per view on average {:.0} nodes tested, {:.0} work units, {:.0} occluder edges \
             written",
            tested as f64 / 20.0,
            units as f64 / 20.0,
            edges as f64 / 20.0
        );
    }
    for (label, range) in [("safe", 0..40), ("safe_ground", 0..20), ("safe_high", 20..40)] {
        let cams = &cameras[range];
        let mut i = 0;
        group.bench_function(label, |b| {
            b.iter(|| {
                safe.cull_into(black_box(&cams[i % cams.len()]), &mut list);
                i += 1;
                black_box(list.stats.triangles_drawn)
            })
        });
    }
    let quad_params = BuildParams {
        grouping: pipeline::Grouping::Quadtree(quadtree::QuadtreeParams::default()),
        ..params.clone()
    };
    let hq = build(&tin, &quad_params, None).expect("quadtree build").hierarchy;
    let qtin = hierarchy_tin(&hq).expect("mesh");
    let qtruth = GroundTruth::new(&qtin);
    let visible: Vec<Vec<bool>> = eyes.iter().map(|e| qtruth.visible_triangles(*e)).collect();
    for columns in [256usize, 1024, 4096] {
        let le = LloydEgbertCuller::new(&hq, columns);
        let (mut tested, mut saved) = (0u64, 0u64);
        for ((camera, eye), visible) in cameras.iter().zip(&eyes).zip(&visible) {
            le.cull_into(camera, &mut list);
            let drawn = list.mask(qtin.num_triangles());
            assert!(
                visible.iter().zip(&drawn).all(|(&v, &d)| d || !v),
                "lloyd-egbert: a visible triangle culled from {eye}"
            );
            tested += u64::from(list.stats.nodes_tested);
            saved += u64::from(list.stats.triangles_culled);
        }
        println!(
            "cull/{name}/lloyd-egbert_w{columns}: quadtree of {} nodes, {}² occluder grid, {} occluders prepared in \
             {:.1} ms; {:.0} nodes tested and {:.0} triangles culled per view on average, none visible",
            hq.nodes.len(),
            le.grid_cells(),
            le.occluder_count(),
            le.precompute_time().as_secs_f64() * 1e3,
            tested as f64 / cameras.len() as f64,
            saved as f64 / cameras.len() as f64
        );
        let mut i = 0;
        group.bench_function(format!("lloyd-egbert_w{columns}"), |b| {
            b.iter(|| {
                le.cull_into(black_box(&cameras[i % cameras.len()]), &mut list);
                i += 1;
                black_box(list.stats.triangles_drawn)
            })
        });
    }
    // The paper's setting: a 90° frustum whose 1,024 columns are the image's width (one face's worth), looking
    // east, north, west and south in turn from each viewpoint.
    let frustums: Vec<Camera> = eyes
        .iter()
        .enumerate()
        .map(|(k, e)| Camera {
            position: e.to_array(),
            yaw: (k % 4) as f64 * std::f64::consts::FRAC_PI_2,
            hfov: std::f64::consts::FRAC_PI_2,
        })
        .collect();
    let le = LloydEgbertCuller::new(&hq, 1024);
    let safe_1024 = SafeCuller::new(
        &h,
        SafeParams {
            columns_per_face: 1024,
            ..SafeParams::default()
        },
    );
    let mut i = 0;
    group.bench_function("lloyd-egbert_w1024_fov90", |b| {
        b.iter(|| {
            le.cull_into(black_box(&frustums[i % frustums.len()]), &mut list);
            i += 1;
            black_box(list.stats.triangles_drawn)
        })
    });
    let mut i = 0;
    group.bench_function("safe_w1024_fov90", |b| {
        b.iter(|| {
            safe_1024.cull_into(black_box(&frustums[i % frustums.len()]), &mut list);
            i += 1;
            black_box(list.stats.triangles_drawn)
        })
    });
    for (method, hierarchy) in [("thesis", &h), ("per_triangle", &per_triangle)] {
        let culler = Culler::new(hierarchy);
        check_against_reference(method, hierarchy, &culler, &checks);
        let mut list = DrawList::default();
        let tested: Vec<u32> = cameras
            .iter()
            .map(|cam| {
                culler.cull_into(cam, &mut list);
                list.stats.nodes_tested
            })
            .collect();
        let mean = |v: &[u32]| v.iter().map(|&n| f64::from(n)).sum::<f64>() / v.len().max(1) as f64;
        println!(
            "cull/{name}/{method}: {} nodes; nodes tested per cull: mean {:.0} (ground {:.0}, high {:.0}), \
             min {}, max {}; matches the reference on {} cameras",
            hierarchy.nodes.len(),
            mean(&tested),
            mean(&tested[..20]),
            mean(&tested[20..]),
            tested.iter().min().unwrap_or(&0),
            tested.iter().max().unwrap_or(&0),
            checks.len()
        );
        let mut i = 0;
        group.bench_function(method, |b| {
            b.iter(|| {
                culler.cull_into(black_box(&cameras[i % cameras.len()]), &mut list);
                i += 1;
                black_box(list.stats.triangles_drawn)
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
