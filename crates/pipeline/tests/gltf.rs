//! glTF export: the `gltf` crate re-imports the same triangles (per group, in hierarchy order) and positions, the
//! hierarchy rebuilt from `extras.tincull` culls like the original, and the Khronos glTF-Validator reports no errors
//! (required when `TINCULL_REQUIRE_GLTF_VALIDATOR=1` or `TINCULL_REQUIRE_GPU=1`, as `scripts/test` sets them).

use std::path::{Path, PathBuf};
use std::process::Command;

use cull::{AnyCuller, Camera, CullMethod, Hierarchy};
use pipeline::gltf::{gltf_files, hierarchy_from_gltf_json, to_glb, to_gltf};

/// Writes the glTF files of `h` for `path`, returning their paths.
fn write_gltf(h: &Hierarchy, path: &Path) -> Vec<PathBuf> {
    gltf_files(h, path)
        .expect("glTF files")
        .into_iter()
        .map(|(p, bytes)| {
            std::fs::write(&p, bytes).expect("write");
            p
        })
        .collect()
}

/// The glTF document of `h` as a JSON value (to read back or damage) and its buffer.
fn gltf_value(h: &Hierarchy) -> (serde_json::Value, Vec<u8>) {
    let (doc, bin) = to_gltf(h, None).expect("glTF");
    (serde_json::to_value(&doc).expect("a JSON value"), bin)
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn bundled(name: &str) -> Hierarchy {
    let obj = workspace().join("meshes").join(name);
    let (t, _) = tin::read_obj(&obj, &tin::ObjImportOptions::default()).expect("the bundled mesh");
    pipeline::build(&t, &pipeline::BuildParams::default(), None)
        .expect("build")
        .hierarchy
}

/// Re-imports with the `gltf` crate: every primitive's triangles are its group's range of the hierarchy's
/// triangles, the groups and the always-visible set cover all triangles once, positions are the f32 local ones.
fn check_reimport(h: &Hierarchy, document: &gltf::Document, bin: &[u8]) {
    let buffers = [bin];
    let mut covered = vec![false; h.num_triangles()];
    let leaves = h.leaf_ranges();
    let mut primitives = 0;
    for mesh in document.meshes() {
        for p in mesh.primitives() {
            primitives += 1;
            assert_eq!(p.mode(), gltf::mesh::Mode::Triangles);
            let reader = p.reader(|b| buffers.get(b.index()).copied());
            let positions: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
            assert_eq!(positions.len(), h.mesh.positions.len());
            for (q, p) in positions.iter().zip(&h.mesh.positions) {
                for k in 0..3 {
                    assert_eq!(q[k], (p[k] - h.origin[k]) as f32);
                }
            }
            let normals: Vec<[f32; 3]> = reader.read_normals().expect("normals").collect();
            assert!(
                normals
                    .iter()
                    .all(|n| ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-5)
            );
            let idx: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
            let tris: Vec<[u32; 3]> = idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let name = mesh.name().expect("named mesh");
            let range = if name == "always_visible" {
                h.always_visible
            } else {
                let g: usize = name.strip_prefix("group_").expect("group_N").parse().expect("N");
                leaves[g]
            };
            assert_eq!(
                &tris[..],
                &h.mesh.triangles[range[0] as usize..range[1] as usize],
                "{name}"
            );
            for t in range[0]..range[1] {
                assert!(!covered[t as usize], "triangle {t} in two primitives");
                covered[t as usize] = true;
            }
        }
    }
    assert!(covered.iter().all(|&c| c), "every triangle is in a primitive");
    let orphans = h.always_visible[0] < h.always_visible[1];
    assert_eq!(primitives, leaves.len() + usize::from(orphans));
    // The always-visible node exists when there are orphans, and holds them (a quadtree has none: no empty node).
    let av = document.nodes().filter(|n| n.name() == Some("always_visible")).count();
    assert_eq!(av, usize::from(orphans));
    assert_eq!(document.nodes().count(), h.nodes.len() + 1 + usize::from(orphans));
    // The node tree mirrors the hierarchy: node 0 carries the origin, hierarchy node i is node i + 1.
    let nodes: Vec<gltf::Node> = document.nodes().collect();
    let (t, r, s) = nodes[0].transform().decomposed();
    let half = std::f32::consts::FRAC_1_SQRT_2;
    assert_eq!(
        (t, r, s),
        (
            [h.origin[0] as f32, h.origin[2] as f32, -(h.origin[1] as f32)],
            [-half, 0.0, 0.0, half],
            [1.0; 3]
        )
    );
    // glTF is +y up: node 0 puts a vertex (x, y, z) of the terrain at (x, z, −y), in world units.
    let m = nodes[0].transform().matrix();
    for p in h.mesh.positions.iter().step_by(97) {
        let q = [0, 1, 2].map(|k| (p[k] - h.origin[k]) as f32);
        let world = [0, 1, 2].map(|r| f64::from(m[0][r] * q[0] + m[1][r] * q[1] + m[2][r] * q[2] + m[3][r]));
        let expected = [p[0], p[2], -p[1]];
        // f32 throughout (the quaternion's matrix too): about 1e-7 of the coordinates involved.
        let scale =
            1.0 + q.iter().map(|c| f64::from(c.abs())).sum::<f64>() + h.origin.iter().map(|c| c.abs()).sum::<f64>();
        for k in 0..3 {
            let tolerance = 1e-6 * scale;
            assert!((world[k] - expected[k]).abs() <= tolerance, "{p:?} lands at {world:?}");
        }
    }
    for (i, n) in h.nodes.iter().enumerate() {
        let kids: Vec<usize> = nodes[i + 1].children().map(|c| c.index()).collect();
        assert_eq!(kids, n.children.iter().map(|&c| c as usize + 1).collect::<Vec<_>>());
        assert_eq!(nodes[i + 1].mesh().is_some(), n.children.is_empty());
    }
}

fn eyes(h: &Hierarchy) -> Vec<Camera> {
    let p = &h.mesh.positions;
    p.iter()
        .step_by(p.len() / 10)
        .map(|v| Camera::all_around([v[0], v[1], v[2] + 2.0]))
        .collect()
}

#[test]
fn glb_reimports_to_the_same_triangles_and_hierarchy() {
    let h = bundled("jacksboro-2k.obj");
    let glb = to_glb(&h).expect("glb");
    let g = gltf::Gltf::from_slice(&glb).expect("the gltf crate reads the .glb");
    let blob = g.blob.clone().expect("a BIN chunk");
    check_reimport(&h, &g.document, &blob);
    // The culling data in extras: the same hierarchy (f32 positions), the same thesis culls.
    let (doc, bin) = gltf_value(&h);
    let back = hierarchy_from_gltf_json(&doc, &bin).expect("rebuilt from extras");
    assert_eq!(back.nodes, h.nodes);
    assert_eq!(back.roots, h.roots);
    assert_eq!(back.always_visible, h.always_visible);
    assert_eq!(back.mesh.triangles, h.mesh.triangles);
    assert_eq!(back.origin, h.origin);
    let (a, b) = (
        AnyCuller::new(&h, CullMethod::Thesis),
        AnyCuller::new(&back, CullMethod::Thesis),
    );
    for c in eyes(&h) {
        assert_eq!(a.cull(&c).ranges, b.cull(&c).ranges);
    }
}

#[test]
fn gltf_with_bin_reimports() {
    let h = bundled("jacksboro-2k.obj");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("terrain.gltf");
    let written = write_gltf(&h, &path);
    assert_eq!(written, vec![path.clone(), dir.path().join("terrain.bin")]);
    let g = gltf::Gltf::open(&path).expect("the gltf crate reads the .gltf");
    let bin = std::fs::read(dir.path().join("terrain.bin")).expect("bin");
    check_reimport(&h, &g.document, &bin);
    // The root's translation is the origin exactly (f64 in the JSON), for readers that keep f64.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).expect("gltf")).expect("the .gltf is JSON");
    let o = h.origin;
    assert_eq!(json["nodes"][0]["translation"], serde_json::json!([o[0], o[2], -o[1]]));
    assert!(
        gltf_files(&h, &dir.path().join("x.bin")).is_err(),
        "a .gltf named .bin is refused"
    );
    // A bad rebuild input names what is missing.
    let e = hierarchy_from_gltf_json(&serde_json::json!({"scenes": [{}]}), &[]).unwrap_err();
    assert!(e.to_string().contains("extras.tincull"), "{e}");
}

fn validator_required() -> bool {
    ["TINCULL_REQUIRE_GLTF_VALIDATOR", "TINCULL_REQUIRE_GPU"]
        .iter()
        .any(|v| std::env::var(v).is_ok_and(|s| s == "1"))
}

#[test]
fn khronos_validator_reports_no_errors() {
    let h = bundled("jacksboro-2k.obj");
    let dir = tempfile::tempdir().expect("tempdir");
    let glb = dir.path().join("terrain.glb");
    let gltf = dir.path().join("terrain.gltf");
    write_gltf(&h, &glb);
    write_gltf(&h, &gltf);
    let script = workspace().join("scripts/gltf-validate.cjs");
    let out = match Command::new("node").arg(&script).arg(&glb).arg(&gltf).output() {
        Ok(o) => o,
        Err(e) => {
            assert!(!validator_required(), "node is missing ({e}): run scripts/install-deps");
            eprintln!("node is missing ({e}): skipping the glTF-Validator check");
            return;
        }
    };
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(2) {
        assert!(!validator_required(), "the glTF-Validator is missing: {stderr}");
        eprintln!("{stderr}: skipping the glTF-Validator check");
        return;
    }
    println!("{stdout}");
    assert!(out.status.success(), "glTF-Validator found errors:\n{stdout}\n{stderr}");
    let reports: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON report per file"))
        .collect();
    assert_eq!(reports.len(), 2);
    for r in &reports {
        assert_eq!(r["errors"], 0, "{r}");
    }
}

/// A quadtree hierarchy has no always-visible triangles: its glTF has no empty `always_visible` node (which the
/// Khronos validator reports as `NODE_EMPTY`) and its grouped OBJ no empty `g orphans` group.
#[test]
fn a_quadtree_export_has_no_empty_orphans() {
    let (t, _) = tin::read_obj(workspace().join("meshes/jacksboro-2k.obj"), &Default::default()).expect("mesh");
    let params = pipeline::BuildParams {
        grouping: pipeline::Grouping::Quadtree(Default::default()),
        ..Default::default()
    };
    let h = pipeline::build(&t, &params, None).expect("build").hierarchy;
    assert_eq!(h.always_visible[0], h.always_visible[1], "a quadtree has no orphans");
    let glb = to_glb(&h).expect("glb");
    let g = gltf::Gltf::from_slice(&glb).expect("the gltf crate reads the .glb");
    check_reimport(&h, &g.document, &g.blob.clone().expect("a BIN chunk"));
    let mut obj = Vec::new();
    pipeline::export::write_grouped_obj_to(&h, "x.mtl", &mut obj).expect("obj");
    let obj = String::from_utf8(obj).expect("utf-8");
    assert!(!obj.contains("g orphans"), "no empty orphans group");
}

/// A document that is not what `to_gltf` wrote is refused with an `ExportError` that names the element at fault,
/// never a panic: wrong types, a missing element, node indices with a gap, counts too large for any buffer, a buffer
/// too short, a hierarchy whose ranges do not fit its mesh.
#[test]
fn a_damaged_gltf_document_names_the_element_at_fault() {
    use pipeline::ExportError;
    use serde_json::json;
    let h = bundled("jacksboro-2k.obj");
    let (doc, bin) = gltf_value(&h);
    let back = hierarchy_from_gltf_json(&doc, &bin).expect("the document reads back");
    assert_eq!((&back.nodes, &back.mesh.triangles), (&h.nodes, &h.mesh.triangles));
    let scene = "/scenes/0/extras/tincull";
    let first_node = (0..)
        .find(|&k| doc["nodes"][k].get("extras").is_some())
        .expect("a hierarchy node");
    let damaged = |pointer: &str, value: serde_json::Value| {
        let mut d = doc.clone();
        *d.pointer_mut(pointer).expect("the element exists") = value;
        hierarchy_from_gltf_json(&d, &bin).expect_err("a damaged document")
    };
    let cases = [
        (
            damaged(&format!("{scene}/sectors"), json!("sixteen")),
            "scenes[0].extras.tincull.sectors",
        ),
        (
            damaged(&format!("{scene}/vertices"), json!(-1)),
            "scenes[0].extras.tincull.vertices",
        ),
        (
            damaged(&format!("{scene}/origin"), json!([1.0, 2.0])),
            "scenes[0].extras.tincull.origin",
        ),
        (
            damaged(&format!("/nodes/{first_node}/extras/tincull/index"), json!(1.5)),
            &format!("nodes[{first_node}].extras.tincull.index"),
        ),
        (
            damaged(&format!("/nodes/{first_node}/extras/tincull/radius"), json!("wide")),
            &format!("nodes[{first_node}].extras.tincull"),
        ),
    ];
    for (e, element) in &cases {
        assert!(matches!(e, ExportError::Json { .. }), "{e:?}");
        assert!(e.to_string().starts_with(&format!("{element}: ")), "{e}");
    }
    let mut d = doc.clone();
    d["scenes"][0]["extras"]["tincull"]
        .as_object_mut()
        .expect("the scene's extras")
        .remove("roots");
    let e = hierarchy_from_gltf_json(&d, &bin).expect_err("no roots");
    assert!(
        matches!(e, ExportError::Malformed(_)) && e.to_string().contains("tincull.roots is missing"),
        "{e}"
    );
    let e = damaged(&format!("/nodes/{first_node}/extras/tincull/index"), json!(100_000));
    assert!(e.to_string().contains("index values are not 0.."), "{e}");
    for (vertices, triangles) in [(u64::MAX, 1), (1, u64::MAX), (u64::MAX / 13, u64::MAX / 13)] {
        let mut d = doc.clone();
        d["scenes"][0]["extras"]["tincull"]["vertices"] = json!(vertices);
        d["scenes"][0]["extras"]["tincull"]["triangles"] = json!(triangles);
        let e = hierarchy_from_gltf_json(&d, &bin).expect_err("counts beyond any buffer");
        assert!(matches!(e, ExportError::Malformed(_)), "{e:?}");
    }
    let e = hierarchy_from_gltf_json(&doc, &bin[..bin.len() - 1]).expect_err("a short buffer");
    assert!(e.to_string().contains("fewer than"), "{e}");
    let e = damaged(&format!("{scene}/always_visible"), json!([0, u32::MAX]));
    assert!(matches!(e, ExportError::Invalid(_)), "{e:?}");
    let e = to_glb(&Hierarchy {
        mesh: cull::Mesh {
            positions: Vec::new(),
            triangles: Vec::new(),
        },
        ..h
    })
    .expect_err("nothing to export");
    assert!(matches!(e, ExportError::NoTriangles), "{e:?}");
}

/// Every scalar of a JSON document, as a JSON pointer (`/nodes/3/extras/tincull/radius`).
fn scalar_pointers(v: &serde_json::Value, at: String, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                scalar_pointers(item, format!("{at}/{i}"), out);
            }
        }
        serde_json::Value::Object(fields) => {
            for (k, item) in fields {
                scalar_pointers(item, format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")), out);
            }
        }
        _ => out.push(at),
    }
}

/// The glTF document and buffer of jacksboro-2k's default build, and every scalar's pointer in the document's
/// `extras` (what `hierarchy_from_gltf_json` reads), made once for all the cases below.
fn damageable() -> &'static (Hierarchy, serde_json::Value, Vec<u8>, Vec<String>) {
    static DOC: std::sync::OnceLock<(Hierarchy, serde_json::Value, Vec<u8>, Vec<String>)> = std::sync::OnceLock::new();
    DOC.get_or_init(|| {
        let h = bundled("jacksboro-2k.obj");
        let (doc, bin) = gltf_value(&h);
        let mut pointers = Vec::new();
        scalar_pointers(&doc, String::new(), &mut pointers);
        pointers.retain(|p| p.contains("/extras/"));
        (h, doc, bin, pointers)
    })
}

mod damaged {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// A tincull glTF with one value of its culling data replaced (by another number, a huge or negative one, a
        /// string, null, an array, an object) and its buffer maybe cut short is read back as a valid hierarchy or
        /// refused with an error, never a panic; what is read back passes every invariant check and culls.
        #[test]
        fn a_gltf_with_any_value_replaced_is_read_or_refused(
            scene_field in any::<bool>(),
            which in 0usize..1_000_000,
            value in prop_oneof![
                any::<i64>().prop_map(serde_json::Value::from),
                any::<u64>().prop_map(serde_json::Value::from),
                proptest::num::f64::NORMAL.prop_map(serde_json::Value::from),
                (0u32..100_000).prop_map(serde_json::Value::from),
                Just(serde_json::Value::Null),
                "[a-z]{0,4}".prop_map(serde_json::Value::from),
                Just(serde_json::json!([1, 2])),
                Just(serde_json::json!({"x": 1})),
            ],
            cut in prop_oneof![Just(0usize), 0usize..64],
        ) {
            let (h, doc, bin, pointers) = damageable();
            // Half the cases damage the scene's own fields (counts, origin, roots, ranges, build), the others any
            // value.
            let scene: Vec<&String> = pointers.iter().filter(|p| p.starts_with("/scenes/")).collect();
            let pointer = if scene_field { scene[which % scene.len()] } else { &pointers[which % pointers.len()] };
            let mut d = doc.clone();
            *d.pointer_mut(pointer).expect("the pointer") = value;
            if let Ok(back) = hierarchy_from_gltf_json(&d, &bin[..bin.len() - cut]) {
                back.check_invariants().expect("what is read back is a valid hierarchy");
                let eye = [back.origin[0], back.origin[1], back.origin[2] + 1000.0];
                for method in CullMethod::ALL {
                    if method.check(&back).is_ok() {
                        let _ = AnyCuller::new(&back, method).cull(&Camera::all_around(eye));
                    }
                }
                prop_assert_eq!(back.mesh.triangles.len(), h.mesh.triangles.len());
            }
        }
    }
}
