//! The pipeline on a small synthetic terrain: the build's figures agree with its hierarchy, the JSON form round
//! trips, the grouped OBJ has one group per leaf with its own material, parameters are checked as `build` checks them
//! (any parameters build or are refused, never a panic), an OBJ with numbers replaced is refused or builds, and the
//! crates of the API are reachable through this one.

use std::path::Path;

use pipeline::export::{from_json, mtl_path, to_json, write_grouped_obj_to, write_mtl_to};
use pipeline::{BuildError, BuildParams, Grouping, QuadtreeParams, build, build_from_regions, build_without_regions};
use tin::{SynthOptions, synth_tin};

fn built() -> pipeline::Build {
    let tin = synth_tin(&SynthOptions::new(600, 3)).expect("synthetic terrain");
    build(&tin, &BuildParams::default(), None).expect("builds")
}

#[test]
fn build_report_matches_the_hierarchy() {
    let b = built();
    let h = &b.hierarchy;
    h.check_invariants().expect("valid hierarchy");
    assert_eq!(b.report.triangles, h.mesh.triangles.len());
    assert_eq!(b.report.nodes, h.nodes.len());
    assert_eq!(b.report.groups, h.leaf_ranges().len());
    assert_eq!(b.report.orphans as u32, h.always_visible[1] - h.always_visible[0]);
    assert_eq!(b.report.visibility_bytes, h.visibility_bytes());
}

#[test]
fn json_round_trip_is_identity() {
    let h = built().hierarchy;
    assert_eq!(from_json(&to_json(&h).expect("json")).expect("parses"), h);
    // The grouping is named as on the command line, and both kinds round trip.
    let v: serde_json::Value = serde_json::from_str(&to_json(&h).expect("json")).expect("JSON");
    assert_eq!(v["build"]["grouping"], "crystal");
    let mut quad = h.clone();
    quad.build.grouping = cull::Grouping::Quadtree {
        built_depth: 3,
        stored_depth: 2,
    };
    let text = to_json(&quad).expect("json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(
        v["build"]["grouping"],
        serde_json::json!({"quadtree": {"built_depth": 3, "stored_depth": 2}})
    );
    assert_eq!(from_json(&text).expect("parses").build.grouping, quad.build.grouping);
    let mut broken = h.clone();
    broken.roots.push(broken.nodes.len() as u32);
    let text = to_json(&broken).expect("json");
    assert!(from_json(&text).is_err(), "the JSON reader checks the invariants");
}

#[test]
fn grouped_obj_has_one_group_and_material_per_leaf() {
    let h = built().hierarchy;
    let (mtl_file, mtl_name) = mtl_path(Path::new("out/g.obj")).expect("an OBJ path");
    assert_eq!(
        (mtl_file.as_path(), mtl_name.as_str()),
        (Path::new("out/g.mtl"), "g.mtl")
    );
    let mut text = Vec::new();
    write_grouped_obj_to(&h, &mtl_name, &mut text).expect("writes");
    let text = String::from_utf8(text).expect("text");
    let mut mtl = Vec::new();
    write_mtl_to(&h, &mut mtl).expect("writes");
    let mtl = String::from_utf8(mtl).expect("text");
    let leaves = h.leaf_ranges().len();
    assert_eq!(text.lines().filter(|l| l.starts_with("g group_")).count(), leaves);
    assert_eq!(mtl.lines().filter(|l| l.starts_with("newmtl group_")).count(), leaves);
    assert_eq!(
        text.lines().filter(|l| l.starts_with("f ")).count(),
        h.mesh.triangles.len()
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("v ")).count(),
        h.mesh.positions.len()
    );
    assert!(text.contains("mtllib g.mtl"));
    assert!(mtl.contains("newmtl orphans"));
}

#[test]
fn quadtree_build_exports_a_valid_quadtree_hierarchy() {
    let tin = synth_tin(&SynthOptions::new(600, 3)).expect("synthetic terrain");
    let mut params = BuildParams {
        sectors: 8,
        subsectors: 2,
        grouping: pipeline::Grouping::Quadtree(pipeline::QuadtreeParams {
            depth: Some(3),
            ..Default::default()
        }),
        ..BuildParams::default()
    };
    let b = build(&tin, &params, None).expect("builds");
    let h = &b.hierarchy;
    h.check_invariants().expect("invariants");
    let q = b.quadtree.as_ref().expect("a quadtree");
    q.check_invariants(&tin).expect("quadtree invariants");
    assert!(b.crystal.is_none());
    assert_eq!(
        h.build.grouping,
        cull::Grouping::Quadtree {
            built_depth: 3,
            stored_depth: 3
        }
    );
    assert_eq!(b.report.grouping, "quadtree");
    assert_eq!(b.report.quadtree_levels.len(), 4);
    assert_eq!(h.roots, vec![0]);
    assert_eq!(h.always_visible, [h.num_triangles() as u32; 2]);
    assert!(
        h.visibility_bytes() as u64 <= q.stored_bytes(),
        "f32 storage can only drop points"
    );
    assert_eq!(
        cull::Hierarchy::from_bytes(&h.to_bytes().expect("encode")).expect("decode"),
        *h
    );
    // The mesh is the TIN's triangles in the quadtree's order.
    for (k, &t) in b.order.iter().enumerate() {
        assert_eq!(h.mesh.triangles[k], tin.triangles()[t as usize]);
    }
    // A byte budget drops the finest level.
    let budget = q.stored_bytes() - 1;
    params.grouping = pipeline::Grouping::Quadtree(pipeline::QuadtreeParams {
        depth: Some(3),
        max_bytes: Some(budget),
        ..Default::default()
    });
    let small = build(&tin, &params, None).expect("builds");
    assert!(small.hierarchy.visibility_bytes() as u64 <= budget);
    assert!(small.hierarchy.nodes.len() < h.nodes.len());
    small.hierarchy.check_invariants().expect("invariants");
}

/// A build without regions is the quadtree build with every region left out: the same mesh, triangle order, nodes
/// and build record, so the safe culler (which reads no region) draws the same triangles from every eye; crystal
/// groups, which grow from the regions, are refused.
#[test]
fn a_build_without_regions_is_the_quadtree_build_less_its_regions() {
    let tin = synth_tin(&SynthOptions::new(600, 3)).expect("synthetic terrain");
    let mut regions_seen = false;
    for depth in [None, Some(0), Some(3)] {
        let params = BuildParams {
            grouping: Grouping::Quadtree(QuadtreeParams {
                depth,
                ..QuadtreeParams::default()
            }),
            ..BuildParams::default()
        };
        let with = build(&tin, &params, None).expect("builds");
        let without = build_without_regions(&tin, &params, None).expect("builds without regions");
        let (h, bare) = (&with.hierarchy, &without.hierarchy);
        bare.check_invariants().expect("invariants");
        let q = without.quadtree.as_ref().expect("a quadtree");
        q.check_invariants(&tin).expect("quadtree invariants");
        regions_seen |= h.nodes.iter().any(|n| !n.regions.is_empty());
        assert!(bare.nodes.iter().all(|n| n.regions.is_empty()));
        let mut stripped = h.clone();
        stripped.nodes.iter_mut().for_each(|n| n.regions.clear());
        assert_eq!(*bare, stripped, "depth {depth:?}");
        assert_eq!(without.order, with.order);
        assert!(without.vertex_regions.is_empty());
        let r = &without.report;
        assert!(r.without_regions && !with.report.without_regions);
        assert_eq!((r.horizon_seconds, r.regions_seconds), (0.0, 0.0));
        assert_eq!(
            (r.nodes, r.groups, r.levels),
            (with.report.nodes, with.report.groups, with.report.levels)
        );
        assert_eq!(r.visibility_bytes, bare.visibility_bytes());
        let (a, b) = (
            cull::SafeCuller::new(h, cull::SafeParams::default()),
            cull::SafeCuller::new(bare, cull::SafeParams::default()),
        );
        let (lo, hi) = (tin.bbox().min, tin.bbox().max);
        for k in 0..12 {
            let f = f64::from(k) / 12.0;
            let eye = [
                lo.x + f * (hi.x - lo.x),
                hi.y - f * (hi.y - lo.y),
                lo.z + (hi.z - lo.z) * (0.3 + f),
            ];
            let camera = cull::Camera::all_around(eye);
            assert_eq!(a.cull(&camera).ranges, b.cull(&camera).ranges, "eye {eye:?}");
        }
    }
    assert!(regions_seen, "the quadtree builds have regions to leave out");
    let crystal = build_without_regions(&tin, &BuildParams::default(), None);
    assert!(matches!(crystal, Err(BuildError::RegionsNeeded)), "{:?}", crystal.err());
}

#[test]
fn an_obj_named_like_its_materials_is_refused() {
    let e = mtl_path(Path::new("same.mtl")).expect_err("would overwrite its own materials");
    assert!(e.to_string().contains("same.mtl"), "{e}");
    assert!(mtl_path(Path::new("noext")).is_ok());
}

#[test]
fn validate_refuses_what_build_refuses() {
    for radius in [f64::NAN, -1.0, 0.0, f64::INFINITY] {
        let params = BuildParams {
            undersampling: Some(radius),
            ..BuildParams::default()
        };
        let err = params
            .validate()
            .expect_err("a radius that is not a positive number of metres");
        assert!(err.to_string().contains("undersampling radius"), "{err}");
        let tin = synth_tin(&SynthOptions::new(50, 1)).expect("a small synthetic terrain");
        assert!(build(&tin, &params, None).is_err(), "build of radius {radius}");
    }
    assert!(BuildParams::default().validate().is_ok());
}

/// The error of a build that must fail.
fn refused(result: Result<pipeline::Build, BuildError>, why: &str) -> BuildError {
    match result {
        Ok(_) => panic!("built, though {why}"),
        Err(e) => e,
    }
}

/// Each way a build fails is its own variant of [`BuildError`], which a library user can match on.
#[test]
fn build_errors_say_which_stage_refused() {
    let tin = synth_tin(&SynthOptions::new(50, 1)).expect("a small synthetic terrain");
    let sectors = BuildParams {
        sectors: 3,
        ..BuildParams::default()
    };
    let e = refused(build(&tin, &sectors, None), "3 sectors");
    assert!(
        matches!(
            e,
            BuildError::Horizon(pipeline::HorizonError::TooFewSectors { sectors: 3 })
        ),
        "{e:?}"
    );
    let mut crystal = BuildParams::default();
    crystal.crystal.max_expanse = -1.0;
    let e = refused(build(&tin, &crystal, None), "a negative expanse");
    assert!(matches!(e, BuildError::Crystal(_)), "{e:?}");
    assert!(e.to_string().contains("max_expanse"), "{e}");
    let quadtree = BuildParams {
        grouping: Grouping::Quadtree(QuadtreeParams {
            depth: Some(99),
            ..QuadtreeParams::default()
        }),
        ..BuildParams::default()
    };
    let e = refused(build(&tin, &quadtree, None), "depth 99");
    assert!(matches!(e, BuildError::Quadtree(_)), "{e:?}");

    // Regions of another terrain (or of another number of sectors) do not fit.
    let built = build(&tin, &BuildParams::default(), None).expect("build");
    let other = synth_tin(&SynthOptions::new(60, 2)).expect("another terrain");
    let e = refused(
        build_from_regions(&other, built.vertex_regions, &BuildParams::default(), [0.0; 2], None),
        "50 rows for 60 vertices",
    );
    match e {
        BuildError::RegionsMismatch {
            rows,
            sectors,
            vertices,
            expected_sectors,
        } => assert_eq!((rows, sectors, vertices, expected_sectors), (50, 16, 60, 16)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn a_user_of_pipeline_alone_reaches_tin_and_cull() {
    let options = pipeline::tin::SynthOptions::new(50, 1);
    let tin: pipeline::tin::Tin = pipeline::tin::synth_tin(&options).expect("a small synthetic terrain");
    let built = build(&tin, &BuildParams::default(), None).expect("build");
    let culler = pipeline::cull::AnyCuller::new(&built.hierarchy, pipeline::cull::CullMethod::default());
    let eye = [0.0, 0.0, tin.bbox().max.z + 10.0];
    let camera = pipeline::cull::Camera::all_around(eye);
    assert!(culler.cull(&camera).stats.triangles_drawn > 0);
}

mod any_parameters {
    use super::*;
    use pipeline::CrystalParams;
    use proptest::prelude::*;

    /// Any float, the awkward ones often.
    fn float() -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(0.0),
            Just(-0.0),
            Just(f64::MIN_POSITIVE),
            Just(f64::MAX),
            -10.0f64..10.0,
            0.0f64..1e6,
            proptest::num::f64::ANY,
        ]
    }

    /// Build parameters, valid ones mostly, every field sometimes far out of range.
    fn params() -> impl Strategy<Value = BuildParams> {
        let count = prop_oneof![0usize..100, Just(usize::MAX), Just(1usize << 40), any::<usize>()];
        let crystal = (
            prop::option::of(count.clone()),
            prop_oneof![0u32..20, Just(u32::MAX), any::<u32>()],
            count,
            float(),
            any::<u64>(),
        )
            .prop_map(
                |(seeds, orphan_passes, min_group, max_expanse, rng_seed)| CrystalParams {
                    seeds,
                    orphan_passes,
                    min_group,
                    max_expanse,
                    rng_seed,
                },
            );
        let quadtree = (
            prop::option::of(prop_oneof![0u32..12, any::<u32>()]),
            prop::option::of(float()),
            prop::option::of(prop_oneof![0u64..100_000, any::<u64>()]),
        )
            .prop_map(|(depth, cell, max_bytes)| QuadtreeParams { depth, cell, max_bytes });
        (
            prop_oneof![8 => 4u32..40, 1 => 0u32..4, 1 => Just(1024), 1 => any::<u32>()],
            prop_oneof![8 => 1u32..8, 1 => Just(0), 1 => any::<u32>()],
            prop_oneof![3 => Just(None), 1 => float().prop_map(Some)],
            crystal,
            prop::option::of(quadtree),
        )
            .prop_map(|(sectors, subsectors, undersampling, crystal, quadtree)| BuildParams {
                sectors,
                subsectors,
                undersampling,
                crystal,
                grouping: quadtree.map_or(Grouping::Crystal, Grouping::Quadtree),
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        /// Any parameters (NaN, infinities, zero, counts near the integers' ends, either grouping) build a valid
        /// hierarchy or are refused with an error, never a panic; parameters that `validate` refuses never build.
        #[test]
        fn any_parameters_build_or_are_refused(params in params()) {
            let tin = synth_tin(&SynthOptions::new(120, 3)).expect("synthetic terrain");
            let checked = params.validate();
            if let Ok(b) = build(&tin, &params, None) {
                prop_assert!(checked.is_ok(), "built with parameters that validate refuses: {params:?}");
                prop_assert!(b.hierarchy.check_invariants().is_ok());
            }
        }
    }
}

mod damaged_obj {
    use super::*;
    use cull::{AnyCuller, Camera, CullMethod};
    use proptest::prelude::*;

    /// The lines of a small synthetic terrain's OBJ, made once.
    fn original() -> &'static Vec<String> {
        static O: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
        O.get_or_init(|| {
            let tin = synth_tin(&SynthOptions::new(60, 2)).expect("synthetic terrain");
            let mut bytes = Vec::new();
            tin::write_obj_to(&tin, &mut bytes).expect("obj");
            String::from_utf8(bytes)
                .expect("utf-8")
                .lines()
                .map(str::to_string)
                .collect()
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// An OBJ with up to three numbers or vertex references replaced (by extremes, NaN, references out of range,
        /// another vertex's index) is refused naming the line, or read into a terrain that builds and culls with every
        /// method; never a panic.
        #[test]
        fn an_obj_with_any_number_replaced_builds_or_is_refused(
            edits in prop::collection::vec((any::<usize>(), any::<usize>(), prop_oneof![
                Just("1e30".to_string()), Just("-1e30".to_string()), Just("1e-30".to_string()), Just("0".to_string()),
                Just("1e300".to_string()), Just("nan".to_string()), Just("-0".to_string()), Just("1".to_string()),
                Just("2".to_string()), Just("60".to_string()), Just("61".to_string()), Just("-1".to_string()),
                Just("4294967296".to_string()), Just("1/2/3".to_string()), Just("3e-310".to_string()),
                (-1000.0f64..1000.0).prop_map(|x| x.to_string()),
                (0u32..70).prop_map(|x| x.to_string()),
            ]), 1..4),
        ) {
            let mut lines = original().clone();
            for (line, token, value) in edits {
                let n = lines.len();
                let l = &mut lines[line % n];
                let mut tokens: Vec<String> = l.split_whitespace().map(str::to_string).collect();
                if tokens.len() > 1 {
                    let k = 1 + token % (tokens.len() - 1);
                    tokens[k] = value;
                    *l = tokens.join(" ");
                }
            }
            let text = lines.join("\n");
            if let Ok((t, _)) = tin::parse_obj(text.as_bytes(), "damaged.obj", &tin::ObjImportOptions::default()) {
                let b = build(&t, &BuildParams { sectors: 8, subsectors: 1, ..BuildParams::default() }, None);
                prop_assert!(b.is_ok(), "read, but the build fails: {:?}", b.err());
                if let Ok(b) = b {
                    let h = &b.hierarchy;
                    let c = h.mesh.positions[0];
                    for method in CullMethod::ALL {
                        if method.check(h).is_ok() {
                            let _ = AnyCuller::new(h, method).cull(&Camera::all_around([c[0], c[1], c[2] + 2.0]));
                        }
                    }
                }
            }
        }
    }
}
