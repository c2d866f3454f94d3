//! Lloyd & Egbert's horizon culling (2002) over quadtrees of several depths and horizon widths, against the thesis'
//! region test and the safe culler over the default crystal build, all scored against one shared ground truth.
//!
//! ```sh
//! cargo run --release -p eval --example lloyd_egbert_compare -- MESH.obj VIEWPOINTS DEPTH[,...] COLUMNS[,...] [SEEDS]
//! # e.g. meshes/jacksboro-10k.obj 20 3,4,5 256,1024,4096
//! ```
//!
//! One build with default parameters (`SEEDS` crystal seeds if given, like `tincull build --seeds`), then one
//! quadtree per depth from the same vertex regions (as `tincull build --grouping quadtree --depth D`). Prints CSV on
//! stdout, one line per (hierarchy, method, columns, class): nodes and leaves of the hierarchy, the method's false
//! culls, occlusion captured, the leaf limit of its own hierarchy, the median over the viewpoints of the cull time
//! (ns; the least of three culls with warm working memory, on whatever core the OS gives), the mean nodes tested per
//! cull, and the culler's preparation time (ms). Columns are per 90° face (`--columns`); `thesis`
//! has none (0).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cull::{AnyCuller, Camera, CullMethod, DrawList, Hierarchy, SafeParams};
use eval::evaluate::{EvalOptions, GroundTruthSet, Leaves, Method, score};
use pipeline::{BuildParams, QuadtreeParams, build, export_quadtree};

/// One hierarchy to cull: grouping, quadtree depth (0 for crystals), the hierarchy, its triangle order in the scored
/// TIN, and the methods with their horizon columns per face.
type Run = (String, u32, Hierarchy, Vec<u32>, Vec<(CullMethod, usize)>);

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if !(5..=6).contains(&args.len()) {
        bail!("usage: lloyd_egbert_compare MESH.obj VIEWPOINTS DEPTH[,...] COLUMNS[,...] [SEEDS]");
    }
    let (tin, _) = tin::read_obj(Path::new(&args[1]), &tin::ObjImportOptions::default())?;
    let viewpoints: usize = args[2].parse().context("VIEWPOINTS")?;
    let depths: Vec<u32> = args[3].split(',').map(str::parse).collect::<Result<_, _>>()?;
    let widths: Vec<usize> = args[4].split(',').map(str::parse).collect::<Result<_, _>>()?;
    // Refused before the ground truth's cost, as `tincull build` and `cull` refuse them.
    for &d in &depths {
        QuadtreeParams {
            depth: Some(d),
            ..QuadtreeParams::default()
        }
        .validate()?;
    }
    for &columns_per_face in &widths {
        SafeParams {
            columns_per_face,
            ..SafeParams::default()
        }
        .check()
        .with_context(|| format!("COLUMNS {columns_per_face}"))?;
    }
    let opts = EvalOptions {
        viewpoints,
        per_triangle: false,
        ..EvalOptions::default()
    };
    let start = Instant::now();
    let truth = GroundTruthSet::compute(&tin, &opts, &|_, _| {})?;
    eprintln!(
        "{}: {} triangles, ground truth {:.1} s",
        args[1],
        tin.num_triangles(),
        start.elapsed().as_secs_f64()
    );
    let mut params = BuildParams::default();
    if let Some(seeds) = args.get(5) {
        params.crystal.seeds = Some(seeds.parse().context("SEEDS")?);
    }
    let b = build(&tin, &params, None)?;
    println!(
        "grouping,depth,nodes,leaves,method,columns,class,viewpoints,viewpoints_with_false_culls,false_culls_max,\
         captured,leaf_limit,cull_ns,nodes_tested,prepare_ms"
    );
    let mut runs: Vec<Run> = vec![(
        "crystal".into(),
        0,
        b.hierarchy.clone(),
        b.order.clone(),
        vec![
            (CullMethod::Thesis, 0),
            (CullMethod::Safe, SafeParams::default().columns_per_face),
        ],
    )];
    for &d in &depths {
        let qp = QuadtreeParams {
            depth: Some(d),
            ..QuadtreeParams::default()
        };
        let q = quadtree::build(&tin, &b.vertex_regions, &qp)?;
        let h = export_quadtree(&tin, &q, &params);
        let mut methods: Vec<(CullMethod, usize)> = widths.iter().map(|&w| (CullMethod::LloydEgbert, w)).collect();
        methods.push((CullMethod::Stewart, 0));
        runs.push(("quadtree".into(), d, h, q.order.clone(), methods));
    }
    for (grouping, depth, h, order, methods) in &runs {
        let ranges = h.leaf_ranges();
        for &(method, columns) in methods {
            let safe = SafeParams {
                columns_per_face: columns.max(2),
                ..SafeParams::default()
            };
            let start = Instant::now();
            let culler = AnyCuller::with_params(h, method, safe);
            let prepare_ms = match &culler {
                AnyCuller::LloydEgbert(c) => c.precompute_time().as_secs_f64() * 1e3,
                _ => start.elapsed().as_secs_f64() * 1e3,
            };
            // Nodes tested per cull and the cull time (warm working memory, the least of 3 culls), over the same
            // viewpoints.
            let mut list = DrawList::default();
            let mut tested = Vec::new();
            for v in &truth.views {
                let camera = Camera::all_around(v.eye.to_array());
                let mut ns = u64::MAX;
                for _ in 0..3 {
                    let start = Instant::now();
                    culler.cull_into(&camera, &mut list);
                    ns = ns.min(start.elapsed().as_nanos() as u64);
                }
                tested.push((v.class.name().to_string(), list.stats.nodes_tested, ns));
            }
            let le_info = match &culler {
                AnyCuller::LloydEgbert(c) => Some((c.grid_cells(), c.occluder_count())),
                _ => None,
            };
            if let Some((cells, occluders)) = le_info {
                eprintln!("{grouping} depth {depth}: {cells}² occluder grid, {occluders} occluders");
            }
            let m = Method {
                name: method.name(),
                culler: Some(culler),
                order: Some(order),
                reach: None,
            };
            let leaves = Leaves {
                ranges: &ranges,
                order: Some(order),
            };
            let e = score(&tin, &truth, &[m], Some(leaves))?;
            for r in &e.rows {
                let s = &r.summary;
                let f = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.4}"));
                let picked: Vec<&(String, u32, u64)> =
                    tested.iter().filter(|t| r.class == "all" || t.0 == r.class).collect();
                let nodes_tested = picked.iter().map(|t| f64::from(t.1)).sum::<f64>() / picked.len().max(1) as f64;
                let mut ns: Vec<u64> = picked.iter().map(|t| t.2).collect();
                ns.sort_unstable();
                let cull_ns = ns.get(ns.len() / 2).copied().unwrap_or(0);
                println!(
                    "{grouping},{depth},{},{},{},{columns},{},{},{},{},{},{},{cull_ns},{nodes_tested:.1},{prepare_ms:.2}",
                    h.nodes.len(),
                    ranges.len(),
                    r.method,
                    r.class,
                    s.viewpoints,
                    s.viewpoints_with_false_culls,
                    f(s.false_culls.map(|x| x.max)),
                    f(s.occlusion_captured.map(|x| x.mean)),
                    f(r.leaf_limit),
                );
            }
        }
    }
    Ok(())
}
