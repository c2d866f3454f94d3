//! Stewart's quadtree baseline in the evaluation: the region test is scored as `stewart` (not `thesis`) over a
//! quadtree hierarchy, and the safe culler and the conservative regions (`safe_regions`) of the quadtree's cells keep
//! zero false culls.

use std::path::Path;

use eval::evaluate::{EvalOptions, evaluate};
use pipeline::{BuildParams, Grouping, QuadtreeParams, build};

fn mesh(name: &str) -> tin::Tin {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../meshes").join(name);
    tin::read_obj(&path, &tin::ObjImportOptions::default())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .0
}

/// `jacksboro-2k` as a quadtree at 16×4 and 64×1, depths 2 to 4: `safe` and `safe_regions` never cull a visible
/// triangle, and the rows are `safe`, `safe_regions`, `stewart`, `frustum_only`, `none`.
#[test]
fn jacksboro_2k_quadtree_is_safe_and_scored_as_stewart() {
    let tin = mesh("jacksboro-2k.obj");
    for (s, k, depth) in [(16, 4, 2), (16, 4, 4), (64, 1, 3)] {
        let params = BuildParams {
            sectors: s,
            subsectors: k,
            grouping: Grouping::Quadtree(QuadtreeParams {
                depth: Some(depth),
                ..QuadtreeParams::default()
            }),
            ..BuildParams::default()
        };
        let b = build(&tin, &params, None).expect("build");
        let opts = EvalOptions {
            viewpoints: 10,
            per_triangle: false,
            ..EvalOptions::default()
        };
        let htin = eval::evaluate::hierarchy_tin(&b.hierarchy).expect("mesh");
        let e = evaluate(&b.hierarchy, &htin, &opts, &|_, _| {}).expect("evaluation");
        let mut methods: Vec<&str> = e.rows.iter().map(|r| r.method.as_str()).collect();
        methods.dedup();
        assert_eq!(
            methods,
            [
                "safe",
                "lloyd-egbert",
                "safe_regions",
                "stewart",
                "frustum_only",
                "none"
            ],
            "{s}x{k} depth {depth}"
        );
        for v in &e.viewpoints {
            for (method, m, _) in &v.methods {
                if method == "safe" || method == "lloyd-egbert" || method == "safe_regions" {
                    assert_eq!(m.false_culls, 0, "{s}x{k} depth {depth}: false culls from {:?}", v.eye);
                }
            }
        }
        let stewart = e
            .rows
            .iter()
            .find(|r| r.method == "stewart" && r.class == "all")
            .expect("stewart row");
        let captured = stewart.summary.occlusion_captured.map_or(0.0, |c| c.mean);
        assert!(captured > 0.0, "{s}x{k} depth {depth}: stewart culls nothing");
        assert!(stewart.leaf_limit.is_some());
    }
}
