//! Run-time culling cost per viewpoint, per method, on the bundled default terrain.
//!
//! `cargo bench --bench cull`. Builds `meshes/jacksboro-10k.obj` with default parameters (16 × 4 sectors), draws 20
//! `ground` and 20 `high` viewpoints (seed 1), and times one cull per viewpoint for the hierarchy and for the
//! per-triangle method. With `TINCULL_BENCH_MESH=path.obj` another mesh is used instead.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use tincull::cull::{Camera, Culler, DrawList};
use tincull::evaluate::{hierarchy_tin, per_triangle_of};
use tincull::pipeline::{BuildParams, build};
use tincull::truth::{ViewpointClass, viewpoints};

fn bench(c: &mut Criterion) {
    let path = std::env::var_os("TINCULL_BENCH_MESH")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/jacksboro-10k.obj"));
    let (tin, _) = tincull::tin::read_obj(&path, &Default::default()).expect("bench mesh");
    let built = build(&tin, &BuildParams::default(), None).expect("build");
    let h = built.hierarchy;
    let htin = hierarchy_tin(&h).expect("mesh");
    let per_triangle = per_triangle_of(&h, &htin).expect("per-triangle regions");
    let mut eyes = viewpoints(&htin, ViewpointClass::Ground, 20, 1);
    eyes.extend(viewpoints(&htin, ViewpointClass::High, 20, 1));
    let cameras: Vec<Camera> = eyes.iter().map(|e| Camera::all_around(e.to_array())).collect();
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut group = c.benchmark_group(format!("cull/{name}"));
    for (method, culler) in [
        ("hierarchy", Culler::new(&h)),
        ("per_triangle", Culler::new(&per_triangle)),
    ] {
        let mut list = DrawList::default();
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
