//! The safe culler's cost and accuracy under several parameter sets (work budget, coarse columns, …) on one
//! hierarchy file, scored against one shared ground truth.
//!
//! ```sh
//! cargo run --release -p eval --example safe_budget -- FILE.tch VIEWPOINTS CLASSES CONFIG [CONFIG ...]
//! # e.g. /tmp/c1m.tch 4 ground,low,high,sky default work=0 work=4000 work=4000,coarse=4
//! ```
//!
//! A `CONFIG` is `default` or comma-separated `key=value` over [`SafeParams::default`]: `columns`, `patch`,
//! `occluders` (occluder budget), `work` (work budget; `0` for unlimited) and `coarse`
//! (coarse columns; `0` refines every visible node); values out of range are refused as `tincull cull` refuses them.
//! Viewpoints: `VIEWPOINTS` per class, 360° view, its own: `truth::viewpoints` with seed 1 for every class (the
//! README's tables were made so), not those of `tincull eval`, which seeds each class apart. Set `TRUTH=0` to skip the ground truth (timings and drawn fractions only), `REPS=N` to
//! time each cull `N` times (default 7; more for a profiler).
//!
//! Prints CSV on stdout, one line per (config, class): the median over the viewpoints of the cull time (ns; each the
//! median of 7 culls with warm working memory, under whatever load the machine has), the means of the drawn fraction,
//! nodes tested, work units and occluder edges written, occlusion captured (culled hidden / hidden, mean over the
//! viewpoints with something hidden), the total false culls, and a digest (hash) of every draw list and its counters:
//! equal digests before and after a change of the culler's code show it culls exactly as before.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cull::{Camera, DrawList, Hierarchy, SafeCuller, SafeParams};
use eval::evaluate::hierarchy_tin;
use truth::{GroundTruth, ViewpointClass, viewpoints};

fn parse_config(s: &str) -> Result<SafeParams> {
    let mut p = SafeParams::default();
    if s == "default" {
        return Ok(p);
    }
    for kv in s.split(',') {
        let (k, v) = kv
            .split_once('=')
            .with_context(|| format!("{kv:?}: expected key=value"))?;
        match k {
            "columns" => p.columns_per_face = v.parse()?,
            "patch" => p.patch = v.parse()?,
            "occluders" => p.occluder_budget = v.parse()?,
            "work" => p.work_budget = v.parse::<usize>().map(|w| if w == 0 { usize::MAX } else { w })?,
            "coarse" => p.coarse_columns = v.parse()?,
            _ => bail!("unknown key {k:?}"),
        }
    }
    p.check().with_context(|| format!("config {s:?}"))?;
    Ok(p)
}

fn median(v: &mut [u64]) -> u64 {
    v.sort_unstable();
    v.get(v.len() / 2).copied().unwrap_or(0)
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 5 {
        bail!("usage: safe_budget FILE.tch VIEWPOINTS CLASSES CONFIG [CONFIG ...]");
    }
    let h = Hierarchy::load(Path::new(&args[1]))?;
    let htin = hierarchy_tin(&h)?;
    let n: usize = args[2].parse().context("VIEWPOINTS")?;
    let classes: Vec<ViewpointClass> = args[3]
        .split(',')
        .map(|c| c.parse::<ViewpointClass>().map_err(|e| anyhow::anyhow!("{e}")))
        .collect::<Result<_>>()?;
    if let Some(twice) = classes.iter().enumerate().find(|(i, c)| classes[..*i].contains(c)) {
        bail!("class {} given twice", twice.1.name());
    }
    let configs: Vec<(String, SafeParams)> = args[4..]
        .iter()
        .map(|s| Ok((s.clone(), parse_config(s)?)))
        .collect::<Result<_>>()?;
    let with_truth = std::env::var("TRUTH").map_or(true, |v| v != "0");
    let reps: usize = std::env::var("REPS").map_or(Ok(7), |v| v.parse()).context("REPS")?;
    let start = Instant::now();
    let truth = GroundTruth::new(&htin);
    let triangles = htin.num_triangles();
    let mut eyes: Vec<(ViewpointClass, Camera, Option<Vec<bool>>)> = Vec::new();
    for &class in &classes {
        for e in viewpoints(&htin, class, n, 1) {
            let visible = with_truth.then(|| truth.visible_triangles(e));
            eyes.push((class, Camera::all_around(e.to_array()), visible));
        }
    }
    eprintln!(
        "{}: {} triangles, {} viewpoints, ground truth {:.1} s",
        args[1],
        triangles,
        eyes.len(),
        start.elapsed().as_secs_f64()
    );
    println!("config,class,cull_ns,drawn_fraction,nodes_tested,work,occluder_edges,captured,false_culls,digest");
    let mut list = DrawList::default();
    for (name, params) in &configs {
        let culler = SafeCuller::new(&h, *params);
        for &class in &classes {
            let (mut times, mut drawn, mut tested, mut work, mut edges) = (Vec::new(), 0.0, 0.0, 0.0, 0.0);
            let (mut captured, mut with_hidden, mut false_culls) = (0.0, 0usize, 0usize);
            let mut views = 0usize;
            let mut digest = DefaultHasher::new();
            for (_, camera, visible) in eyes.iter().filter(|e| e.0 == class) {
                culler.cull_into(camera, &mut list);
                let mut t = vec![0u64; reps.max(1)];
                for x in &mut t {
                    let s = Instant::now();
                    culler.cull_into(camera, &mut list);
                    *x = s.elapsed().as_nanos() as u64;
                }
                times.push(median(&mut t));
                list.ranges.hash(&mut digest);
                format!("{:?}", list.stats).hash(&mut digest);
                let s = list.stats;
                views += 1;
                drawn += f64::from(s.triangles_drawn) / triangles as f64;
                tested += f64::from(s.nodes_tested);
                work += f64::from(s.work);
                edges += f64::from(s.occluder_edges);
                if let Some(visible) = visible {
                    let mask = list.mask(triangles);
                    let (mut hidden, mut culled_hidden) = (0usize, 0usize);
                    for (&v, &d) in visible.iter().zip(&mask) {
                        if !v {
                            hidden += 1;
                            culled_hidden += usize::from(!d);
                        } else if !d {
                            false_culls += 1;
                        }
                    }
                    if hidden > 0 {
                        with_hidden += 1;
                        captured += culled_hidden as f64 / hidden as f64;
                    }
                }
            }
            let k = views.max(1) as f64;
            let captured = if with_hidden > 0 {
                format!("{:.4}", captured / with_hidden as f64)
            } else {
                String::new()
            };
            println!(
                "{name:?},{},{},{:.4},{:.0},{:.0},{:.0},{captured},{false_culls},{:016x}",
                class.name(),
                median(&mut times),
                drawn / k,
                tested / k,
                work / k,
                edges / k,
                digest.finish(),
            );
        }
    }
    Ok(())
}
