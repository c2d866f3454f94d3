//! Pins the accuracy of every culling method on the bundled meshes: false culls and occlusion captured per method
//! and viewpoint class, at fixed seeds (default build parameters, `--rng-seed 1`; 6 viewpoints per class,
//! `--view-seed 1`, 360° view). The build, the viewpoints and the ground truth are deterministic, so the counts are
//! exact; a change to any stage that moves them must update this table on purpose (run with `--nocapture` to print
//! the new one).

use std::path::Path;

use tincull::evaluate::{EvalOptions, evaluate, hierarchy_tin};
use tincull::pipeline::{BuildParams, build};

/// `(method, class, viewpoints with false culls, total false culls, most in one viewpoint, occlusion captured
/// mean)`; `None` where nothing was hidden.
type Row = (&'static str, &'static str, usize, usize, usize, Option<f64>);

fn measure(mesh: &str) -> Vec<(String, String, usize, usize, usize, Option<f64>)> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes").join(mesh);
    let (tin, _) = tincull::tin::read_obj(&path, &Default::default()).expect("bundled mesh");
    let built = build(&tin, &BuildParams::default(), None).expect("builds");
    let htin = hierarchy_tin(&built.hierarchy).expect("hierarchy mesh");
    let opts = EvalOptions {
        viewpoints: 6,
        rng_seed: 1,
        ..EvalOptions::default()
    };
    let e = evaluate(&built.hierarchy, &htin, &opts, &|_, _| {}).expect("evaluates");
    e.rows
        .iter()
        .map(|r| {
            let s = &r.summary;
            let fc = s.false_culls.as_ref();
            let total = fc.map_or(0, |f| (f.mean * f.count as f64).round() as usize);
            let max = fc.map_or(0, |f| f.max as usize);
            let occ = s.occlusion_captured.as_ref().map(|o| o.mean);
            (
                r.method.clone(),
                r.class.clone(),
                s.viewpoints_with_false_culls,
                total,
                max,
                occ,
            )
        })
        .collect()
}

fn check(mesh: &str, pinned: &[Row]) {
    let got = measure(mesh);
    let table: String = got
        .iter()
        .map(|(m, c, v, t, x, o)| {
            let o = o.map_or("None".to_string(), |o| format!("Some({o:.6})"));
            format!("    (\"{m}\", \"{c}\", {v}, {t}, {x}, {o}),\n")
        })
        .collect();
    println!("{mesh}:\n{table}");
    assert_eq!(got.len(), pinned.len(), "{mesh}: rows changed; now:\n{table}");
    for (g, p) in got.iter().zip(pinned) {
        assert_eq!(
            (g.0.as_str(), g.1.as_str()),
            (p.0, p.1),
            "{mesh}: row order; now:\n{table}"
        );
        assert_eq!(
            (g.2, g.3, g.4),
            (p.2, p.3, p.4),
            "{mesh} {} {}: false culls; now:\n{table}",
            p.0,
            p.1
        );
        match (g.5, p.5) {
            (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-6, "{mesh} {} {}: occlusion {a} vs {b}", p.0, p.1),
            (a, b) => assert_eq!(a, b, "{mesh} {} {}: occlusion; now:\n{table}", p.0, p.1),
        }
    }
}

#[test]
fn jacksboro_2k_accuracy_is_pinned() {
    check("jacksboro-2k.obj", JACKSBORO_2K);
}

#[test]
fn jacksboro_10k_accuracy_is_pinned() {
    check("jacksboro-10k.obj", JACKSBORO_10K);
}

#[test]
fn synth_5k_accuracy_is_pinned() {
    check("synth-5k.obj", SYNTH_5K);
}

const JACKSBORO_2K: &[Row] = &[
    ("hierarchy", "ground", 0, 0, 0, Some(0.147706)),
    ("hierarchy", "low", 0, 0, 0, Some(0.036385)),
    ("hierarchy", "high", 0, 0, 0, Some(0.024847)),
    ("hierarchy", "valley", 0, 0, 0, Some(0.104626)),
    ("hierarchy", "ridge", 0, 0, 0, Some(0.066572)),
    ("hierarchy", "sky", 0, 0, 0, Some(0.000000)),
    ("hierarchy", "all", 0, 0, 0, Some(0.063356)),
    ("per_triangle", "ground", 3, 11, 7, Some(0.495040)),
    ("per_triangle", "low", 2, 5, 3, Some(0.521308)),
    ("per_triangle", "high", 5, 28, 13, Some(0.485787)),
    ("per_triangle", "valley", 0, 0, 0, Some(0.556348)),
    ("per_triangle", "ridge", 5, 30, 16, Some(0.558289)),
    ("per_triangle", "sky", 5, 38, 21, Some(0.273972)),
    ("per_triangle", "all", 20, 112, 21, Some(0.481791)),
    ("frustum_only", "ground", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "low", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "high", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "valley", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "ridge", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "sky", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "all", 0, 0, 0, Some(0.000000)),
    ("none", "ground", 0, 0, 0, Some(0.000000)),
    ("none", "low", 0, 0, 0, Some(0.000000)),
    ("none", "high", 0, 0, 0, Some(0.000000)),
    ("none", "valley", 0, 0, 0, Some(0.000000)),
    ("none", "ridge", 0, 0, 0, Some(0.000000)),
    ("none", "sky", 0, 0, 0, Some(0.000000)),
    ("none", "all", 0, 0, 0, Some(0.000000)),
];

const JACKSBORO_10K: &[Row] = &[
    ("hierarchy", "ground", 0, 0, 0, Some(0.268587)),
    ("hierarchy", "low", 0, 0, 0, Some(0.348428)),
    ("hierarchy", "high", 2, 18, 13, Some(0.274770)),
    ("hierarchy", "valley", 0, 0, 0, Some(0.310849)),
    ("hierarchy", "ridge", 1, 9, 9, Some(0.254722)),
    ("hierarchy", "sky", 2, 9, 7, Some(0.051764)),
    ("hierarchy", "all", 5, 36, 13, Some(0.251520)),
    ("per_triangle", "ground", 1, 9, 9, Some(0.713818)),
    ("per_triangle", "low", 4, 87, 80, Some(0.743525)),
    ("per_triangle", "high", 6, 342, 134, Some(0.701207)),
    ("per_triangle", "valley", 0, 0, 0, Some(0.681937)),
    ("per_triangle", "ridge", 5, 171, 51, Some(0.732205)),
    ("per_triangle", "sky", 6, 447, 120, Some(0.493428)),
    ("per_triangle", "all", 22, 1056, 134, Some(0.677687)),
    ("frustum_only", "ground", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "low", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "high", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "valley", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "ridge", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "sky", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "all", 0, 0, 0, Some(0.000000)),
    ("none", "ground", 0, 0, 0, Some(0.000000)),
    ("none", "low", 0, 0, 0, Some(0.000000)),
    ("none", "high", 0, 0, 0, Some(0.000000)),
    ("none", "valley", 0, 0, 0, Some(0.000000)),
    ("none", "ridge", 0, 0, 0, Some(0.000000)),
    ("none", "sky", 0, 0, 0, Some(0.000000)),
    ("none", "all", 0, 0, 0, Some(0.000000)),
];

const SYNTH_5K: &[Row] = &[
    ("hierarchy", "ground", 0, 0, 0, Some(0.224924)),
    ("hierarchy", "low", 0, 0, 0, Some(0.198592)),
    ("hierarchy", "high", 0, 0, 0, Some(0.008887)),
    ("hierarchy", "valley", 0, 0, 0, Some(0.324577)),
    ("hierarchy", "ridge", 1, 4, 4, Some(0.157307)),
    ("hierarchy", "sky", 0, 0, 0, Some(0.058685)),
    ("hierarchy", "all", 1, 4, 4, Some(0.162162)),
    ("per_triangle", "ground", 1, 54, 54, Some(0.702252)),
    ("per_triangle", "low", 2, 49, 29, Some(0.760825)),
    ("per_triangle", "high", 6, 70, 26, Some(0.439376)),
    ("per_triangle", "valley", 0, 0, 0, Some(0.788930)),
    ("per_triangle", "ridge", 5, 297, 165, Some(0.693866)),
    ("per_triangle", "sky", 6, 62, 20, Some(0.537451)),
    ("per_triangle", "all", 20, 532, 165, Some(0.653783)),
    ("frustum_only", "ground", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "low", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "high", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "valley", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "ridge", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "sky", 0, 0, 0, Some(0.000000)),
    ("frustum_only", "all", 0, 0, 0, Some(0.000000)),
    ("none", "ground", 0, 0, 0, Some(0.000000)),
    ("none", "low", 0, 0, 0, Some(0.000000)),
    ("none", "high", 0, 0, 0, Some(0.000000)),
    ("none", "valley", 0, 0, 0, Some(0.000000)),
    ("none", "ridge", 0, 0, 0, Some(0.000000)),
    ("none", "sky", 0, 0, 0, Some(0.000000)),
    ("none", "all", 0, 0, 0, Some(0.000000)),
];
