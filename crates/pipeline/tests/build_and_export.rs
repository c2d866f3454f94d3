//! The pipeline on a small synthetic terrain: the build's figures agree with its hierarchy, the JSON form round
//! trips, and the grouped OBJ has one group per leaf with its own material.

use std::path::Path;

use pipeline::export::{from_json, mtl_path, to_json, write_grouped_obj_to, write_mtl_to};
use pipeline::{BuildParams, build};
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
fn an_obj_named_like_its_materials_is_refused() {
    let e = mtl_path(Path::new("same.mtl")).expect_err("would overwrite its own materials");
    assert!(e.to_string().contains("same.mtl"), "{e}");
    assert!(mtl_path(Path::new("noext")).is_ok());
}
