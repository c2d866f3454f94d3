//! Stewart's quadtree (1997) against the thesis' crystal hierarchy, with the same horizons and regions, scored
//! against one shared ground truth (issue 14).
//!
//! ```sh
//! cargo run --release -p eval --example stewart_compare -- MESH.obj VIEWPOINTS SECTORSxSUBSECTORS[,...] DEPTH[,...]
//! # e.g. meshes/jacksboro-10k.obj 20 16x4,64x4 5,4,3
//! ```
//!
//! For every sector configuration: one build (horizons, vertex regions, crystals), then one quadtree per depth from
//! the same vertex regions. Prints CSV on stdout, one line per (hierarchy, method, class): build seconds (horizons +
//! regions + grouping), visibility bytes, nodes, the method's false culls, occlusion captured, the leaf limit and the
//! median cull time; before a sector configuration's lines, one `# levels` line per quadtree with the bytes of each
//! of its levels (JSON). The configurations and depths are checked before the ground truth is computed.
//! Methods: `safe` (run-time conservative horizon), the region test (`thesis` over crystals, `stewart` over the
//! quadtree), and `safe_regions` (the same region test over conservative regions of the same nodes,
//! `pipeline::conservative_hierarchy`).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cull::{AnyCuller, CullMethod};
use eval::evaluate::{EvalOptions, GroundTruthSet, Leaves, Method, score, standard_methods};
use pipeline::{BuildParams, QuadtreeParams, build, export_quadtree};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 {
        bail!("usage: stewart_compare MESH.obj VIEWPOINTS SxK[,SxK...] DEPTH[,DEPTH...]");
    }
    let (tin, _) = tin::read_obj(Path::new(&args[1]), &tin::ObjImportOptions::default())?;
    let viewpoints: usize = args[2].parse().context("VIEWPOINTS")?;
    let configs: Vec<(u32, u32)> = args[3]
        .split(',')
        .map(|c| {
            let bad = || format!("{c:?}: expected SECTORSxSUBSECTORS, e.g. 16x4");
            let (s, k) = c.split_once('x').with_context(bad)?;
            Ok((s.parse().with_context(bad)?, k.parse().with_context(bad)?))
        })
        .collect::<Result<_>>()?;
    let depths: Vec<u32> = args[4].split(',').map(str::parse).collect::<Result<_, _>>()?;
    for &(s, k) in &configs {
        horizon::SectorConfig::new(s, k).with_context(|| format!("{s}x{k}"))?;
    }
    for &d in &depths {
        QuadtreeParams {
            depth: Some(d),
            ..QuadtreeParams::default()
        }
        .validate()?;
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
    println!(
        "sectors,subsectors,grouping,depth,build_s,grouping_s,bytes,nodes,leaves,method,class,viewpoints,\
         false_culls_mean,false_culls_max,viewpoints_with_false_culls,captured,leaf_limit,cull_ns,visible_fraction"
    );
    for &(s, k) in &configs {
        let params = BuildParams {
            sectors: s,
            subsectors: k,
            ..BuildParams::default()
        };
        let b = build(&tin, &params, None)?;
        let shared = b.report.horizon_seconds + b.report.regions_seconds;
        let mut hierarchies = vec![(
            "crystal".to_string(),
            0u32,
            shared + b.report.grouping_seconds,
            b.report.grouping_seconds,
            b.hierarchy.clone(),
            b.order.clone(),
        )];
        for &d in &depths {
            let qp = QuadtreeParams {
                depth: Some(d),
                ..QuadtreeParams::default()
            };
            let start = Instant::now();
            let q = quadtree::build(&tin, &b.vertex_regions, &qp)?;
            let h = export_quadtree(&tin, &q, &params);
            let seconds = start.elapsed().as_secs_f64();
            if d == *depths.iter().max().unwrap_or(&d) {
                println!("# levels {s}x{k} {}", serde_json::to_string(&q.levels)?);
            }
            hierarchies.push(("quadtree".into(), d, shared + seconds, seconds, h, q.order.clone()));
        }
        for (grouping, depth, build_s, grouping_s, h, order) in &hierarchies {
            let mut methods = standard_methods(h, None, Some(order), Default::default());
            // The thesis' test over conservative regions of the same nodes (crystal groups or quadtree cells).
            let start = Instant::now();
            let conservative = pipeline::conservative_hierarchy(h);
            eprintln!(
                "{s}x{k} {grouping} depth {depth}: conservative regions {:.1} s",
                start.elapsed().as_secs_f64()
            );
            methods.push(Method {
                name: "safe_regions",
                culler: Some(AnyCuller::new(&conservative, CullMethod::Thesis)),
                order: Some(order),
                reach: Some(eval::evaluate::conservative_reach(h)),
            });
            let ranges = h.leaf_ranges();
            let leaves = Leaves {
                ranges: &ranges,
                order: Some(order),
            };
            let e = score(&tin, &truth, &methods, Some(leaves))?;
            for r in &e.rows {
                if r.method == "none" || r.method == "frustum_only" {
                    continue;
                }
                let m = &r.summary;
                let f = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.4}"));
                println!(
                    "{s},{k},{grouping},{depth},{build_s:.3},{grouping_s:.3},{},{},{},{},{},{},{},{},{},{},{},{:.0},{:.4}",
                    h.visibility_bytes(),
                    h.nodes.len(),
                    ranges.len(),
                    r.method,
                    r.class,
                    m.viewpoints,
                    f(m.false_culls.map(|x| x.mean)),
                    f(m.false_culls.map(|x| x.max)),
                    m.viewpoints_with_false_culls,
                    f(m.occlusion_captured.map(|x| x.mean)),
                    f(r.leaf_limit),
                    r.cull_ns,
                    r.visible_fraction
                );
            }
        }
    }
    Ok(())
}
