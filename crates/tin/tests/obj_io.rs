//! OBJ import and export: round trips, agreement with tobj, and one test per malformed case.

use std::io::BufReader;
use std::path::Path;

use glam::DVec3;
use proptest::prelude::*;
use tin::obj::ObjLineError as K;
use tin::{DedupePolicy, ObjImportOptions, Tin, TinError, UpAxis, parse_obj, read_obj, triangulate, write_obj_to};

const KEEP: ObjImportOptions = ObjImportOptions {
    keep_faces: true,
    dedupe: DedupePolicy::Reject,
    up: UpAxis::Z,
};
const DELAUNAY: ObjImportOptions = ObjImportOptions {
    keep_faces: false,
    dedupe: DedupePolicy::Reject,
    up: UpAxis::Z,
};

fn obj_text(tin: &Tin) -> Vec<u8> {
    let mut out = Vec::new();
    write_obj_to(tin, &mut out).expect("write to memory");
    out
}

fn assert_same_bits(a: &Tin, b: &Tin) {
    assert_eq!(a.num_vertices(), b.num_vertices());
    for (v, (p, q)) in a.positions().iter().zip(b.positions()).enumerate() {
        assert_eq!(
            p.to_array().map(f64::to_bits),
            q.to_array().map(f64::to_bits),
            "vertex {v}: {p} vs {q}"
        );
    }
    assert_eq!(a.triangles(), b.triangles());
}

/// The (path-free) line error of a failed import.
fn line_error(r: tin::Result<(Tin, tin::ObjImportReport)>) -> (usize, K) {
    match r {
        Err(TinError::ObjLine { line, kind, .. }) => (line, kind),
        Err(e) => panic!("expected a line error, got {e}"),
        Ok(_) => panic!("expected a line error, got a TIN"),
    }
}

fn keep(text: &str) -> tin::Result<(Tin, tin::ObjImportReport)> {
    parse_obj(text.as_bytes(), "test.obj", &KEEP)
}

fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        // UTM-like, full mantissa.
        (0.0f64..1.0).prop_map(|u| 500_000.0 + u * 1000.0),
        // Any magnitude from 2^-30 to 2^30, either sign.
        (0.0f64..1.0, -30i32..30, any::<bool>())
            .prop_map(|(m, e, s)| (1.0 + m) * 2f64.powi(e) * if s { -1.0 } else { 1.0 }),
        // Small integers and signed zeros.
        (-5i32..5).prop_map(f64::from),
        Just(-0.0),
    ]
}

/// Heights over the whole range import accepts (0, or magnitudes in [2^-100, 2^100], full mantissas); values
/// outside it are refused at import (`coordinates_out_of_range_are_refused_at_import`), and the text form of every
/// f64 is checked by `display_of_f64_round_trips`.
fn height() -> impl Strategy<Value = f64> {
    prop_oneof![
        (1.0f64..2.0, -100i32..100, any::<bool>()).prop_map(|(m, e, s)| m * 2f64.powi(e) * if s { -1.0 } else { 1.0 }),
        Just(0.0),
        Just(-0.0),
        -100.0f64..3000.0,
    ]
}

fn random_tin() -> impl Strategy<Value = Option<Tin>> {
    prop::collection::vec((coordinate(), coordinate(), height()), 3..60).prop_map(|pts| {
        let points: Vec<DVec3> = pts.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
        triangulate(&points, DedupePolicy::KeepHighest).ok().map(|(t, _)| t)
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// With keep_faces, import after export is the identity: positions bit for bit, triangles in order.
    #[test]
    fn export_then_import_is_identity(tin in random_tin()) {
        let Some(tin) = tin else { return Ok(()) };
        let (back, report) = parse_obj(&obj_text(&tin), "rt.obj", &KEEP).expect("exported TIN re-imports");
        assert_same_bits(&tin, &back);
        prop_assert_eq!(report.vertices_read, tin.num_vertices());
        prop_assert_eq!(report.faces_read, tin.num_triangles());
        prop_assert_eq!(report.merged_duplicates + report.dropped_lower + report.unreferenced_dropped, 0);
    }

    /// A y-up file (the z-up TIN written as `(x, z, −y)`, as a y-up exporter would) read with [`UpAxis::Y`] is the
    /// z-up TIN again, bit for bit, in both modes: the rotation keeps the faces' orientation, so kept faces pass the
    /// height-field checks unchanged.
    #[test]
    fn y_up_import_undoes_the_y_up_rotation(tin in random_tin()) {
        let Some(tin) = tin else { return Ok(()) };
        // What a y-up exporter writes: each vertex as (x, z, −y), the faces as they are.
        let vertices = tin.positions().iter().map(|p| format!("v {} {} {}\n", p.x, p.z, -p.y));
        let faces = tin.triangles().iter().map(|t| format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
        let y_up: String = vertices.chain(faces).collect();
        let (kept, _) = parse_obj(y_up.as_bytes(), "y.obj", &ObjImportOptions { up: UpAxis::Y, ..KEEP })
            .expect("the y-up file reads with up y");
        assert_same_bits(&tin, &kept);
        let (direct, _) = parse_obj(&obj_text(&tin), "z.obj", &DELAUNAY).expect("z-up");
        let (rotated, _) = parse_obj(y_up.as_bytes(), "y.obj", &ObjImportOptions { up: UpAxis::Y, ..DELAUNAY })
            .expect("y-up");
        prop_assert_eq!(direct.num_vertices(), rotated.num_vertices());
        for (p, q) in direct.positions().iter().zip(rotated.positions()) {
            prop_assert_eq!(p.to_array().map(f64::to_bits), q.to_array().map(f64::to_bits));
        }
        prop_assert_eq!(direct.num_triangles(), rotated.num_triangles());
        prop_assert_eq!(UpAxis::Y.to_z_up(DVec3::new(1.0, 2.0, 3.0)), DVec3::new(1.0, -3.0, 2.0));
    }

    /// The default import Delaunay-triangulates the file's vertices: the same TIN as triangulating them directly.
    #[test]
    fn default_import_triangulates_vertices(tin in random_tin()) {
        let Some(tin) = tin else { return Ok(()) };
        let (back, report) = parse_obj(&obj_text(&tin), "rt.obj", &DELAUNAY).expect("re-imports");
        // Same vertices in the same order; the triangles are a Delaunay triangulation of them (compared by count
        // and area: with cocircular points the triangulation is not unique, and spade's choice among them is not
        // even stable from run to run when its bulk loader defers vertices).
        let (direct, _) = triangulate(tin.positions(), DedupePolicy::Reject).expect("triangulates");
        prop_assert_eq!(direct.num_vertices(), back.num_vertices());
        for (p, q) in direct.positions().iter().zip(back.positions()) {
            prop_assert_eq!(p.to_array().map(f64::to_bits), q.to_array().map(f64::to_bits));
        }
        prop_assert_eq!(direct.num_triangles(), back.num_triangles());
        let area = |t: &Tin| (0..t.num_triangles()).map(|i| t.triangle_area_xy(i)).sum::<f64>();
        prop_assert!((area(&direct) - area(&back)).abs() <= 1e-9 * area(&direct));
        prop_assert_eq!(report.faces_read, tin.num_triangles());
        prop_assert!(!report.kept_faces);
    }

    /// OBJ written in every reference style, with groups, normals, comments and CRLF, reads the same as the plain
    /// export, and tobj (f64) reads the same corner positions face by face.
    #[test]
    fn styles_agree_with_tobj(tin in random_tin(), styles in prop::collection::vec(0u8..6, 64)) {
        let Some(tin) = tin else { return Ok(()) };
        let mut text = String::from("# header comment\r\nmtllib none.mtl\r\no terrain\r\n");
        for p in tin.positions() {
            text.push_str(&format!("v {} {} {}  # a vertex\r\n", p.x, p.y, p.z));
        }
        text.push_str("vt 0 0\nvt 1 1\nvn 0 0 1\ns off\n");
        let n = tin.num_vertices() as i64;
        for (t, tri) in tin.triangles().iter().enumerate() {
            let style = styles[t % styles.len()];
            if style == 5 {
                text.push_str(&format!("g part{t}\nusemtl m{t}\n"));
            }
            let refs: Vec<String> = tri.iter().map(|&v| {
                let a = i64::from(v) + 1;
                match style {
                    0 | 5 => format!("{a}"),
                    1 => format!("{a}/1"),
                    2 => format!("{a}//1"),
                    3 => format!("{a}/2/1"),
                    _ => format!("{}", a - n - 1), // relative
                }
            }).collect();
            text.push_str(&format!("f {}\n", refs.join(" ")));
        }
        let (back, report) = parse_obj(text.as_bytes(), "styles.obj", &KEEP).expect("reads");
        assert_same_bits(&tin, &back);
        prop_assert!(report.ignored_statements >= 5);

        let (models, _) = tobj::load_obj_buf(
            &mut BufReader::new(text.as_bytes()),
            &tobj::LoadOptions::default(),
            |_| Err(tobj::LoadError::OpenFileFailed),
        ).expect("tobj reads it");
        let mut corners = Vec::new();
        for m in &models {
            for &i in &m.mesh.indices {
                let i = i as usize;
                corners.push(DVec3::new(m.mesh.positions[3 * i], m.mesh.positions[3 * i + 1], m.mesh.positions[3 * i + 2]));
            }
        }
        let mine: Vec<DVec3> = (0..back.num_triangles()).flat_map(|t| back.corners(t)).collect();
        prop_assert_eq!(corners.len(), mine.len());
        for (a, b) in corners.iter().zip(&mine) {
            prop_assert_eq!(a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits));
        }
    }

    /// Arbitrary bytes never panic the importer, in either mode.
    #[test]
    fn arbitrary_bytes_do_not_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        let _ = parse_obj(&bytes, "fuzz.obj", &KEEP);
        let _ = parse_obj(&bytes, "fuzz.obj", &DELAUNAY);
    }

    /// Soups of plausible OBJ words never panic, and errors always name a line within the text.
    #[test]
    fn token_soup_does_not_panic(words in prop::collection::vec(
        prop_oneof![
            Just("v"), Just("f"), Just("\n"), Just("1"), Just("2"), Just("-1"), Just("0"), Just("3.5"), Just("1e"),
            Just("nan"), Just("inf"), Just("1/2/3"), Just("//"), Just("#"), Just("g"), Just("-0"), Just("4"),
            Just("1e308"), Just("1e309"), Just("-2"), Just("\r\n"),
        ], 0..200)) {
        let text = words.join(" ");
        let lines = text.split('\n').count();
        for opts in [KEEP, DELAUNAY, ObjImportOptions { keep_faces: true, dedupe: DedupePolicy::KeepHighest, up: UpAxis::Z }] {
            if let Err(TinError::ObjLine { line, .. }) = parse_obj(text.as_bytes(), "soup.obj", &opts) {
                prop_assert!(line >= 1 && line <= lines);
            }
        }
    }
}

#[test]
fn file_round_trip_is_atomic_and_exact() {
    let dir = tempfile::tempdir().expect("tempdir");
    let points: Vec<DVec3> = (0..200)
        .map(|i| {
            let f = i as f64;
            DVec3::new(
                500_000.0 + (f * 0.618).fract() * 1e3,
                4.8e6 + (f * 0.377).fract() * 1e3,
                (f * 0.1).sin() * 100.0,
            )
        })
        .collect();
    let (tin, _) = triangulate(&points, DedupePolicy::Reject).expect("triangulates");
    let path = dir.path().join("t.obj");
    let mut text = Vec::new();
    write_obj_to(&tin, &mut text).expect("writes");
    std::fs::write(&path, text).expect("writes the file");
    let (back, _) = read_obj(&path, &KEEP).expect("reads");
    assert_same_bits(&tin, &back);
}

#[test]
fn display_of_f64_round_trips() {
    // The writer relies on `{}` being the shortest representation that parses back to the same bits.
    let specials = [
        0.1,
        1.0 / 3.0,
        -0.0,
        f64::MIN_POSITIVE,
        5e-324,
        f64::MAX,
        f64::EPSILON,
        4_799_999.999_999_999,
        123_456.789_012_345_67,
    ];
    for x in specials {
        let s = format!("{x}");
        assert_eq!(s.parse::<f64>().expect("parses").to_bits(), x.to_bits(), "{s}");
    }
}

#[test]
fn missing_file_is_io_error() {
    match read_obj(Path::new("/definitely/not/here.obj"), &KEEP) {
        Err(TinError::Io { path, source }) => {
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
            assert!(path.ends_with("here.obj"));
        }
        other => panic!("expected Io, got {other:?}"),
    }
}

#[test]
fn empty_file_has_no_vertices() {
    for text in ["", "\n\n", "# only a comment\n", "g group\nvt 0 0\n"] {
        match parse_obj(text.as_bytes(), "empty.obj", &DELAUNAY) {
            Err(TinError::Format { message, .. }) => assert!(message.contains("no vertices"), "{message}"),
            other => panic!("expected Format, got {other:?}"),
        }
    }
}

#[test]
fn face_index_out_of_range_names_the_line() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n";
    assert_eq!(
        line_error(parse_obj(text.as_bytes(), "x.obj", &DELAUNAY)),
        (5, K::IndexOutOfRange { index: 9, vertices: 3 })
    );
    // Relative index reaching before the first vertex.
    let text = "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n";
    assert_eq!(
        line_error(keep(text)),
        (3, K::IndexOutOfRange { index: -3, vertices: 2 })
    );
    // Forward references are fine.
    let text = "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    assert_eq!(keep(text).expect("forward references").0.num_triangles(), 1);
}

#[test]
fn non_finite_vertex_names_the_line() {
    for (text, line) in [
        ("v 0 0 0\nv nan 1 2\n", 2),
        ("v 0 0 0\n# c\nv 1 inf 2\n", 3),
        ("v 1 2 1e400\n", 1),
    ] {
        let (l, kind) = line_error(parse_obj(text.as_bytes(), "x.obj", &DELAUNAY));
        assert_eq!(l, line, "{text}");
        assert!(matches!(kind, K::NonFinite { .. }), "{kind:?}");
    }
    assert_eq!(line_error(keep("v 1 2 3 0\n")), (1, K::BadWeight { w: 0.0 }));
}

#[test]
fn duplicate_xy_with_different_z_is_a_wall() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 5\nf 1 2 3\n";
    let expected = K::DuplicateXy {
        vertex: 4,
        other_vertex: 2,
        other_line: 2,
        x: 1.0,
        y: 0.0,
        z: 5.0,
        other_z: 0.0,
    };
    assert_eq!(
        line_error(parse_obj(text.as_bytes(), "x.obj", &DELAUNAY)),
        (4, expected.clone())
    );
    assert_eq!(line_error(keep(text)), (4, expected));
    // Keep-highest resolves it: the higher vertex takes the face.
    let highest = ObjImportOptions {
        keep_faces: true,
        dedupe: DedupePolicy::KeepHighest,
        up: UpAxis::Z,
    };
    let (tin, report) = parse_obj(text.as_bytes(), "x.obj", &highest).expect("resolved");
    assert_eq!(report.dropped_lower, 1);
    assert_eq!(tin.num_vertices(), 3);
    assert!(tin.positions().contains(&DVec3::new(1.0, 0.0, 5.0)));
    // Equal duplicates are welded silently and counted.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 1 0 0\nf 1 2 3\nf 5 4 3\n";
    let (tin, report) = keep(text).expect("welded");
    assert_eq!(report.merged_duplicates, 1);
    assert_eq!(tin.num_vertices(), 4);
    assert_eq!(
        tin.neighbours()[0].iter().filter(|&&n| n == 1).count(),
        1,
        "the welded faces are neighbours"
    );
}

#[test]
fn vertical_faces_are_degenerate() {
    // A wall face: three vertices on one line in x,y.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 5\nf 1 2 3\nf 1 2 4\n";
    assert_eq!(line_error(keep(text)), (6, K::DegenerateFace));
    // A wall from welding: keep-highest merges 2 and 4, collapsing the face.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 9\nf 1 2 3\nf 4 3 2\n";
    let highest = ObjImportOptions {
        keep_faces: true,
        dedupe: DedupePolicy::KeepHighest,
        up: UpAxis::Z,
    };
    assert_eq!(
        line_error(parse_obj(text.as_bytes(), "x.obj", &highest)),
        (6, K::DegenerateFace)
    );
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n")),
        (4, K::DegenerateFace)
    );
}

#[test]
fn non_manifold_edges_name_both_lines() {
    // Three triangles on edge 1-2.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 2 2 0\nf 1 2 3\nf 2 1 4\nf 1 2 5\n";
    let (line, kind) = line_error(keep(text));
    assert_eq!(line, 8);
    assert_eq!(
        kind,
        K::NonManifoldEdge {
            a: 1,
            b: 2,
            other_line: 6
        }
    );
}

#[test]
fn inconsistent_orientation_names_both_lines() {
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 4 3\n";
    assert_eq!(
        line_error(keep(text)),
        (6, K::InconsistentOrientation { first_line: 5 })
    );
    // All clockwise is flipped, not an error.
    let (tin, _) = keep("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 3 2 1\nf 4 3 1\n").expect("flipped");
    assert!((0..2).all(|t| tin.triangle_area_xy(t) > 0.0));
}

#[test]
fn overlapping_faces_are_not_a_height_field() {
    // Two separate triangles, the second one's corner inside the first.
    let text = "v 0 0 0\nv 4 0 0\nv 0 4 0\nv 1 1 9\nv 6 1 9\nv 1 6 9\nf 1 2 3\nf 4 5 6\n";
    assert_eq!(line_error(keep(text)), (8, K::Overlap { other_line: 7 }));
    // Both counter-clockwise, sharing a vertex, one inside the other.
    let text = "v 0 0 0\nv 4 0 0\nv 0 4 0\nv 3 1 1\nv 1 3 1\nf 1 2 3\n# the other\nf 1 4 5\n";
    assert_eq!(line_error(keep(text)), (8, K::Overlap { other_line: 6 }));
    // Touching along an edge without sharing it (a T-junction) is not an overlap; at the edge's height there it
    // leaves the surface whole, at another height it is a crack, named by the face and the vertex.
    let text = "v 0 0 0\nv 4 0 0\nv 0 4 0\nv 2 0 0\nv 3 -1 0\nf 1 2 3\nf 4 5 2\n";
    assert!(keep(text).is_ok());
    let text = "v 0 0 0\nv 4 0 0\nv 0 4 0\nv 2 0 7\nv 3 -1 0\nf 1 2 3\nf 4 5 2\n";
    assert_eq!(line_error(keep(text)), (6, K::Crack { vertex: 4 }));
}

#[test]
fn truncated_lines_are_reported() {
    assert_eq!(line_error(keep("v 0 0 0\nv 1.0 2.")), (2, K::VertexArity { found: 2 }));
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1.0 2.0 3.5e")),
        (2, K::BadNumber { token: "3.5e".into() })
    );
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2")),
        (4, K::FaceArity { found: 2 })
    );
    // "3/" is a valid reference (empty texture index): that file is complete.
    assert!(keep("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/").is_ok());
    // A number cut before its exponent digits, in a face.
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3e")),
        (4, K::BadReference { token: "3e".into() })
    );
    // Cuts that leave lines which still read: the report says the text has no final line break.
    let opts = ObjImportOptions {
        keep_faces: true,
        ..ObjImportOptions::default()
    };
    for (text, unterminated) in [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3", true),
        ("v 0 0 0\nv 1 0 0\nv 0 1. 0\nf 1 2 3\n", false),
        ("v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n", false),
    ] {
        let (_, report) = parse_obj(text.as_bytes(), "m.obj", &opts).expect("reads");
        assert_eq!(report.unterminated, unterminated, "{text:?}");
    }
}

#[test]
fn garbage_is_reported() {
    assert_eq!(
        line_error(keep("hello world\n")),
        (
            1,
            K::UnknownStatement {
                keyword: "hello".into()
            }
        )
    );
    // Binary without a known signature (a PNG is named as such: `foreign_files_are_named_by_their_first_bytes`).
    let binary = b"\x89XYZ\r\n\x1a\n\0\0\0\rIHDR";
    let (line, kind) = line_error(parse_obj(binary, "x.obj", &KEEP));
    assert_eq!(line, 1);
    assert_eq!(kind, K::NotUtf8);
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 a 3\n")),
        (4, K::BadReference { token: "a".into() })
    );
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")),
        (4, K::BadReference { token: "0".into() })
    );
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2/3/4 2 3\n")),
        (
            4,
            K::BadReference {
                token: "1/2/3/4".into()
            }
        )
    );
    assert_eq!(line_error(keep("v 0 0 0 0 0\n")), (1, K::VertexArity { found: 5 }));
    // The message names the file and the line.
    let e = keep("v 0 0 0\nfoo\n").expect_err("garbage");
    assert_eq!(
        e.to_string(),
        "test.obj:2: unknown statement \"foo\" (not an OBJ file?)"
    );
}

#[test]
fn byte_order_mark_and_crlf_are_accepted() {
    let text = "\u{feff}v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n";
    let (tin, report) = keep(text).expect("valid");
    assert_eq!((report.vertices_read, tin.num_triangles()), (3, 1));
    // A mark anywhere else is garbage.
    assert_eq!(
        line_error(keep("v 0 0 0\n\u{feff}v 1 0 0\n")),
        (
            2,
            K::UnknownStatement {
                keyword: "\u{feff}v".into()
            }
        )
    );
}

#[test]
fn keep_faces_needs_faces() {
    match keep("v 0 0 0\nv 1 0 0\nv 0 1 0\n") {
        Err(TinError::Format { message, .. }) => assert!(message.contains("no faces"), "{message}"),
        other => panic!("expected Format, got {other:?}"),
    }
}

#[test]
fn too_few_or_collinear_vertices() {
    match parse_obj(b"v 0 0 0\nv 1 1 1\nv 2 2 2\n", "line.obj", &DELAUNAY) {
        Err(TinError::Format { message, .. }) => assert!(message.contains("collinear"), "{message}"),
        other => panic!("expected Format, got {other:?}"),
    }
}

#[test]
fn unreferenced_vertices_are_dropped_and_counted() {
    let text = "v 9 9 9\nv 0 0 0\nv 1 0 1\nv 1 1 2\nv 0 1 3\nf 2 3 4\nf 2 4 5\nv 5 5 5\n";
    let (tin, report) = keep(text).expect("valid");
    assert_eq!(report.unreferenced_dropped, 2);
    assert_eq!(report.vertices_read, 6);
    assert_eq!(tin.num_vertices(), 4);
    assert_eq!(tin.position(0), DVec3::new(0.0, 0.0, 0.0));
    // The stray first vertex is gone, so the TIN's indices are the file's minus one.
    assert_eq!(tin.triangles(), &[[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn polygons_are_triangulated() {
    // A square with a midpoint on its bottom edge, and an L-shaped (concave) hexagon beside it.
    let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4 5\n\
                v 3 0 0\nv 5 0 0\nv 5 1 0\nv 4 1 0\nv 4 2 0\nv 3 2 0\nf 6 7 8 9 10 11\n";
    let (tin, report) = keep(text).expect("valid");
    assert_eq!(report.polygons_read, 2);
    assert_eq!(tin.num_triangles(), 3 + 4);
    let area: f64 = (0..tin.num_triangles()).map(|t| tin.triangle_area_xy(t)).sum();
    assert_eq!(area, 4.0 + 3.0);
    assert!((0..tin.num_triangles()).all(|t| tin.triangle_area_xy(t) > 0.0));
    // A self-intersecting bow tie.
    let text = "v 0 0 0\nv 2 2 0\nv 2 0 0\nv 0 2 0\nf 1 2 3 4\n";
    assert_eq!(line_error(keep(text)), (5, K::BadPolygon));
    // A lopsided one has non-zero signed area; whatever ear clipping makes of it must not pass.
    let text = "v 0 0 0\nv 3 3 0\nv 3 0 0\nv 0 1 0\nf 1 2 3 4\n";
    let (line, kind) = line_error(keep(text));
    assert_eq!(line, 5);
    assert!(matches!(kind, K::BadPolygon | K::Overlap { other_line: 5 }), "{kind:?}");
    // All vertices on a line.
    assert_eq!(
        line_error(keep("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n")),
        (5, K::BadPolygon)
    );
}

#[test]
fn large_height_field_imports_with_faces() {
    // A 100 x 100 grid, exported and re-imported with its faces (the overlap check runs on 19,602 triangles).
    let n = 100;
    let points: Vec<DVec3> = (0..n * n)
        .map(|i| DVec3::new((i % n) as f64 * 10.0, (i / n) as f64 * 10.0, ((i * 7919) % 97) as f64))
        .collect();
    let (tin, _) = triangulate(&points, DedupePolicy::Reject).expect("grid");
    let (back, report) = parse_obj(&obj_text(&tin), "grid.obj", &KEEP).expect("valid");
    assert_same_bits(&tin, &back);
    assert_eq!(report.triangles, 2 * (n - 1) * (n - 1));
}

/// A coordinate no stage can handle is refused at import, naming the file, the line and the 1-based vertex
/// (before, `info` and `tin` accepted z = 1e300 and `build` refused it later with a 0-based vertex and no file).
#[test]
fn coordinates_out_of_range_are_refused_at_import() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 1e300\nf 1 2 3\n";
    let (line, kind) = line_error(keep(text));
    assert_eq!(line, 3);
    assert!(
        matches!(kind, K::OutOfRange { vertex: 3, axis: "z", value } if value == 1e300),
        "{kind:?}"
    );
    let e = keep(text).expect_err("refused").to_string();
    assert!(
        e.contains("test.obj:3") && e.contains("vertex 3") && e.contains("1e300"),
        "{e}"
    );
    let (_, kind) = line_error(keep("v 1e-200 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
    assert!(
        matches!(
            kind,
            K::OutOfRange {
                vertex: 1,
                axis: "x",
                ..
            }
        ),
        "{kind:?}"
    );
    assert!(keep("v 5e5 5e6 1e4\nv 500001 5e6 0\nv 5e5 5000001 0\nf 1 2 3\n").is_ok());
}

/// A DEM or a mesh of another format given where an OBJ is read is named, with what to do, not parsed as text.
#[test]
fn foreign_files_are_named_by_their_first_bytes() {
    let cases: [(&[u8], &str); 6] = [
        (b"II*\0\x08\0\0\0", "a TIFF: name it .tif"),
        (b"MM\0*\0\0\0\x08", "a TIFF"),
        (b"\x89PNG\r\n\x1a\n\0\0", "a PNG"),
        (b"\x93NUMPY\x01\0", "a NumPy array"),
        (b"ply\nformat ascii 1.0\n", "a PLY mesh"),
        (b"solid t\n facet normal 0 0 1\n", "an ASCII STL"),
    ];
    for (bytes, needle) in cases {
        match parse_obj(bytes, "terrain.dat", &DELAUNAY) {
            Err(e @ TinError::Format { .. }) => {
                let m = e.to_string();
                assert!(
                    m.contains("terrain.dat") && m.contains("not an OBJ mesh") && m.contains(needle),
                    "{m}"
                );
            }
            other => panic!("{needle}: {:?}", other.map(|(t, _)| t.num_vertices())),
        }
    }
    // A text OBJ whose first statement is a comment about STL is still an OBJ.
    let text = "# solid facet\nv 0 0 0\nv 1 0 0\nv 0 1 1\n";
    assert!(parse_obj(text.as_bytes(), "ok.obj", &DELAUNAY).is_ok());
}
