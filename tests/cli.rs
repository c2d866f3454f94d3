//! End-to-end tests of the `tincull` binary: every command on the bundled meshes, bad input, determinism.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{fails_with, json, mesh, ok, run, s};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tincull"))
}

#[test]
fn info_reports_the_bundled_mesh() {
    let v = json(&["info", s(&mesh("jacksboro-2k.obj")), "--json"]);
    assert_eq!(v["vertices"], 2000);
    assert_eq!(v["height_field"], true);
    assert!(v["triangles"].as_u64().expect("count") > 3800);
    assert!(v["relief"].as_f64().expect("relief") > 500.0);
}

#[test]
fn synth_is_deterministic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let [a, b, c] = ["a.obj", "b.obj", "c.obj"].map(|n| dir.path().join(n));
    ok(&["synth", "-o", s(&a), "--vertices", "3000", "--rng-seed", "7", "-q"]);
    ok(&["synth", "-o", s(&b), "--vertices", "3000", "--rng-seed", "7", "-q"]);
    ok(&["synth", "-o", s(&c), "--vertices", "3000", "--rng-seed", "8", "-q"]);
    let read = |p: &Path| std::fs::read(p).expect("written");
    assert_eq!(read(&a), read(&b));
    assert_ne!(read(&a), read(&c));
    let v = json(&["info", s(&a), "--json"]);
    assert_eq!(v["vertices"], 3000);
}

#[test]
fn tin_simplifies_an_ascii_grid() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asc = dir.path().join("hill.asc");
    let mut text =
        String::from("ncols 40\nnrows 30\nxllcorner 1000\nyllcorner 2000\ncellsize 10\nNODATA_value -9999\n");
    for r in 0..30 {
        let row: Vec<String> = (0..40)
            .map(|c| {
                if (r, c) == (10, 10) {
                    "-9999".into()
                } else {
                    format!("{}", (r * c) % 17 + r)
                }
            })
            .collect();
        text += &row.join(" ");
        text += "\n";
    }
    std::fs::write(&asc, text).expect("fixture");
    let obj = dir.path().join("hill.obj");
    let v = json(&["tin", s(&asc), "-o", s(&obj), "--vertices", "200", "--json"]);
    assert_eq!(v["vertices"], 200);
    assert_eq!(v["stopped_by"], "vertex_budget");
    assert_eq!(v["voids"], 1);
    assert!(v["max_error"].as_f64().expect("error") > 0.0);
    // `-o -`: the same OBJ on standard output, and nothing else there.
    let piped = ok(&["tin", s(&asc), "-o", "-", "--vertices", "200"]);
    assert_eq!(piped.stdout, std::fs::read(&obj).expect("written"));
    fails_with(
        &["tin", s(&asc), "-o", "-", "--vertices", "200", "--json"],
        "both write to standard output",
    );
    let v = json(&["tin", s(&asc), "-o", s(&obj), "--max-error", "0", "--json"]);
    assert_eq!(v["max_error"], 0.0);
    assert!(matches!(v["stopped_by"].as_str(), Some("exact" | "error_bound")), "{v}");
    let info = json(&["info", s(&obj), "--json"]);
    assert_eq!(info["vertices"], v["vertices"]);
}

/// A grid in degrees: with its `.prj` it is put into metres and `info` says how; without, `info` and `tin` warn that
/// degrees look read as metres.
#[test]
fn a_geographic_asc_is_converted_or_warned_about() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asc = dir.path().join("deg.asc");
    let mut text = "ncols 12\nnrows 10\nxllcorner -122.5\nyllcorner 46.8\ncellsize 0.000833333333333\n".to_string();
    for r in 0..10 {
        let row: Vec<String> = (0..12).map(|c| format!("{}", 1000 + (r * 7 + c * 3) % 23)).collect();
        text += &row.join(" ");
        text += "\n";
    }
    std::fs::write(&asc, text).expect("fixture");
    let out = ok(&["info", s(&asc)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("look like degrees read as metres"), "{stderr}");
    assert!(
        stderr.contains("spacing 8.333e-4 x 8.333e-4 m and a north-west sample at (-122."),
        "{stderr}"
    );
    let obj = dir.path().join("deg.obj");
    let out = ok(&["tin", s(&asc), "-o", s(&obj), "--keep-grid"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("look like degrees"));
    std::fs::write(
        dir.path().join("deg.prj"),
        "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563]],PRIMEM[\"Greenwich\",0],\
         UNIT[\"degree\",0.0174532925199433]]",
    )
    .expect("prj");
    let out = ok(&["info", s(&asc)]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(!stderr.contains("look like degrees"), "{stderr}");
    assert!(stdout.contains("to metres") && stdout.contains("deg.prj"), "{stdout}");
    let v = json(&["info", s(&asc), "--json", "-q"]);
    // 1/1200 of a degree of latitude.
    assert!(
        (v["dem"]["spacing"][1].as_f64().expect("dy") - 111_320.0 / 1200.0).abs() < 1e-9,
        "{v}"
    );
    assert!(
        v["dem"]["to_metres"]
            .as_str()
            .expect("said")
            .contains("degrees to metres")
    );
}

/// A terrain exported y-up (height in y) is named as such, whether it fails as vertical walls or reads; mesh-only
/// flags given for a DEM grid, DEM-only flags given for a mesh, and either given for a hierarchy are errors naming
/// the flag, not ignored.
#[test]
fn a_y_up_mesh_gets_a_hint() {
    let dir = tempfile::tempdir().expect("tempdir");
    let text = std::fs::read_to_string(mesh("jacksboro-2k.obj")).expect("bundled mesh");
    let y_up: String = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let v: Vec<f64> = rest.split_whitespace().map(|w| w.parse().expect("number")).collect();
                format!("v {} {} {}\n", v[0], v[2], -v[1])
            }
            None => format!("{l}\n"),
        })
        .collect();
    let obj = dir.path().join("yup.obj");
    std::fs::write(&obj, y_up).expect("fixture");
    fails_with(&["info", s(&obj)], "the mesh looks y-up");
    let out = ok(&["info", s(&obj), "--dedupe", "keep-highest"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("looks y-up"));
    let out = ok(&["info", s(&mesh("jacksboro-2k.obj"))]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("y-up"));
    // The hint names the way out, and `--up y` reads the file as the z-up mesh it was made from, exactly (the
    // rotation only moves and negates coordinates), with no warning; it is refused for a DEM grid.
    fails_with(&["info", s(&obj)], "give --up y");
    let out = ok(&["info", s(&obj), "--up", "y", "--json"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("y-up"));
    let read: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let orig = json(&["info", s(&mesh("jacksboro-2k.obj")), "--json"]);
    for key in ["bbox", "import", "relief", "slivers"] {
        assert_eq!(read[key], orig[key], "{key}");
    }
    // `--up y` given for a file that is z-up already is named as such (the hint told to give it), whether the
    // rotated mesh fails or reads.
    fails_with(
        &["info", s(&mesh("jacksboro-2k.obj")), "--up", "y"],
        "the file looks z-up already; leave out --up y",
    );
    let flat = dir.path().join("flat.obj");
    std::fs::write(
        &flat,
        "v 0 0 0\nv 100 0 1\nv 100 100 2\nv 0 100 3\nv 50 50 1\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
    )
    .expect("fixture");
    let out = run(&["info", s(&flat), "--up", "y"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the file looks z-up already; leave out --up y"),
        "{stderr}"
    );
    assert!(!stderr.contains("give --up y"), "{stderr}");
    let grid = common::small_asc(dir.path(), "g.asc");
    fails_with(&["info", s(&grid), "--up", "y"], "--up y applies to OBJ meshes");
    // A y-up file's z = 0 becomes y = -0 on rotation: the bounding box shows 0, not "-0.000".
    let yup0 = dir.path().join("yup0.obj");
    std::fs::write(
        &yup0,
        "v 0 1 0\nv 100 2 0\nv 100 3 -100\nv 0 1 -100\nv 50 5 -50\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
    )
    .expect("fixture");
    let text = String::from_utf8_lossy(&ok(&["info", s(&yup0), "--up", "y"]).stdout).into_owned();
    assert!(
        text.contains("bbox          x 0.000 .. 100.000, y 0.000 .. 100.000, z 1.000 .. 5.000"),
        "{text}"
    );
    fails_with(
        &[
            "tiles",
            "plan",
            s(&grid),
            "--up",
            "y",
            "-o",
            s(&dir.path().join("p.json")),
        ],
        "applies to OBJ",
    );
    // The other mesh-only flags are refused for a DEM too, by every command, rather than ignored.
    fails_with(
        &["build", s(&grid), "--keep-faces", "-o", s(&dir.path().join("g.tch"))],
        "--keep-faces applies to OBJ meshes",
    );
    fails_with(
        &["info", s(&grid), "--dedupe", "keep-highest"],
        "--dedupe keep-highest applies to OBJ meshes",
    );
    fails_with(
        &[
            "tiles",
            "plan",
            s(&grid),
            "--keep-faces",
            "-o",
            s(&dir.path().join("p.json")),
        ],
        "--keep-faces applies to OBJ meshes",
    );
    assert!(!dir.path().join("g.tch").exists() && !dir.path().join("p.json").exists());
    // And the DEM-only flags for a mesh.
    let obj = mesh("jacksboro-2k.obj");
    fails_with(&["info", s(&obj), "--z-scale", "3"], "--z-scale 3 applies to DEM grids");
    // A height scale that would flatten or poison the terrain is refused by name, before anything is read.
    for bad in ["0", "-0", "NaN", "inf"] {
        fails_with(&["info", s(&obj), "--z-scale", bad], "'--z-scale <Z_SCALE>'");
    }
    fails_with(&["info", s(&obj), "--band", "2"], "--band 2 applies to DEM grids");
    fails_with(
        &["build", s(&obj), "--spacing", "1,1", "-o", s(&dir.path().join("g.tch"))],
        "--spacing 1,1 applies to DEM grids",
    );
    // A negative spacing is read as the value it is (not as another flag) and refused for what it is.
    fails_with(
        &["info", s(&obj), "--spacing", "-1,1"],
        "spacing must be positive and finite, got \"-1,1\"",
    );
    fails_with(
        &[
            "tiles",
            "plan",
            s(&obj),
            "--z-scale",
            "2",
            "-o",
            s(&dir.path().join("p.json")),
        ],
        "--z-scale 2 applies to DEM grids",
    );
    fails_with(
        &["info", s(&obj), "--dem-vertices", "500"],
        "--dem-vertices 500 applies to DEM grids",
    );
    // A flag given is refused even at its default value: it was given for a reason that does not apply.
    fails_with(&["info", s(&obj), "--z-scale", "1"], "--z-scale 1 applies to DEM grids");
    fails_with(
        &["info", s(&obj), "--dem-vertices", "10000"],
        "--dem-vertices 10000 applies to DEM grids",
    );
    fails_with(
        &["info", s(&grid), "--dedupe", "reject"],
        "--dedupe reject applies to OBJ meshes",
    );
    fails_with(&["info", s(&grid), "--up", "z"], "--up z applies to OBJ meshes");
    fails_with(
        &[
            "tiles",
            "plan",
            s(&obj),
            "--max-error",
            "1",
            "-o",
            s(&dir.path().join("p.json")),
        ],
        "--max-error 1 applies to a DEM's tiles",
    );
    assert!(!dir.path().join("g.tch").exists() && !dir.path().join("p.json").exists());
    // And both for a hierarchy, which holds its mesh.
    let tch = dir.path().join("j.tch");
    ok(&["build", s(&obj), "-o", s(&tch), "-q"]);
    fails_with(
        &["info", s(&tch), "--keep-faces"],
        "--keep-faces applies to an OBJ mesh input",
    );
    let png = dir.path().join("r.png");
    fails_with(
        &["render", s(&tch), "--z-scale", "2", "-o", s(&png)],
        "--z-scale 2 applies to a DEM grid input",
    );
    assert!(!png.exists());
    fails_with(
        &["info", s(&tch), "--dem-vertices", "5"],
        "--dem-vertices 5 applies to a DEM grid input",
    );
}

/// A GeoTIFF in US survey feet without a vertical unit, and an `.asc` whose `.prj` is in feet: every command that reads
/// them says the heights were taken to be feet and how to undo that; x, y and heights come out in metres.
#[test]
fn dems_in_feet_are_read_in_metres_with_a_warning() {
    use tiff::encoder::{TiffEncoder, colortype};
    use tiff::tags::Tag;
    let dir = tempfile::tempdir().expect("tempdir");
    let tif = dir.path().join("ft.tif");
    let (w, h) = (6u32, 5u32);
    let data: Vec<f32> = (0..w * h)
        .map(|i| 1000.0 + (i % 7) as f32 * 10.0 + (i / 3) as f32)
        .collect();
    {
        let file = std::fs::File::create(&tif).expect("create");
        let mut enc = TiffEncoder::new(file).expect("encoder");
        let mut img = enc.new_image::<colortype::Gray32Float>(w, h).expect("image");
        let d = img.encoder();
        // Projected, US survey feet (3076 = 9003), no VerticalUnitsGeoKey.
        let keys: [u16; 12] = [1, 1, 0, 2, 1024, 0, 1, 1, 3076, 0, 1, 9003];
        d.write_tag(Tag::GeoKeyDirectoryTag, &keys[..]).expect("tag");
        d.write_tag(Tag::ModelPixelScaleTag, &[10.0f64, 10.0, 0.0][..])
            .expect("tag");
        d.write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 1000.0, 2000.0, 0.0][..])
            .expect("tag");
        img.write_data(&data).expect("data");
    }
    let out = ok(&["info", s(&tif), "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("taken to be in the same feet") && err.contains("--z-scale 3.28083333"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let bbox = v["bbox"]["max"].as_array().expect("bbox");
    let survey = 1200.0 / 3937.0;
    let top = bbox[2].as_f64().expect("z");
    let highest = data.iter().fold(f32::MIN, |a, &b| a.max(b)) as f64;
    assert!((top - highest * survey).abs() < 1e-9, "{top}");
    let obj = dir.path().join("ft.obj");
    let out = ok(&["tin", s(&tif), "--vertices", "12", "-o", s(&obj)]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--z-scale"));
    // An ESRI grid whose .prj is a state plane in US survey feet: the same warning.
    let asc = dir.path().join("ft.asc");
    std::fs::write(
        &asc,
        "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 100\n1 2 3\n4 9 6\n7 8 5\n",
    )
    .expect("asc");
    std::fs::write(
        dir.path().join("ft.prj"),
        "PROJCS[\"NAD_1983_StatePlane_Texas_North_Central_FIPS_4202_Feet\",GEOGCS[\"GCS_North_American_1983\",\
         DATUM[\"D_North_American_1983\",SPHEROID[\"GRS_1980\",6378137.0,298.257222101]],PRIMEM[\"Greenwich\",0.0],\
         UNIT[\"Degree\",0.0174532925199433]],PROJECTION[\"Lambert_Conformal_Conic\"],UNIT[\"Foot_US\",0.3048006096012192]]",
    )
    .expect("prj");
    let out = ok(&["info", s(&asc)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("Foot_US") && err.contains("--z-scale 3.28083333"), "{err}");
    // The old ESRI text form stating the heights' unit (`Zunits METERS`): coordinates in feet, heights as written,
    // and no warning.
    std::fs::write(
        dir.path().join("ft.prj"),
        "Projection    STATEPLANE\nFipszone      4202\nDatum         NAD83\nZunits        METERS\nUnits         FEET\n",
    )
    .expect("prj");
    let out = ok(&["info", s(&asc), "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("--z-scale"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["bbox"]["max"][2].as_f64(), Some(9.0), "heights in metres as written");
    assert_eq!(
        v["bbox"]["max"][0].as_f64(),
        Some(250.0 * survey),
        "x in US survey feet"
    );
}

/// A GeoTIFF with GDAL's internal nodata mask (an image tagged as a mask after the samples): the samples it marks
/// invalid are voids, and `info` says so.
#[test]
fn a_geotiff_mask_is_applied() {
    use tiff::encoder::{TiffEncoder, colortype};
    use tiff::tags::Tag;
    let dir = tempfile::tempdir().expect("tempdir");
    let tif = dir.path().join("masked.tif");
    {
        let mut enc = TiffEncoder::new(std::fs::File::create(&tif).expect("create")).expect("encoder");
        let mut img = enc.new_image::<colortype::Gray32Float>(4, 3).expect("image");
        let keys: [u16; 12] = [1, 1, 0, 2, 1024, 0, 1, 1, 3076, 0, 1, 9001];
        img.encoder()
            .write_tag(Tag::GeoKeyDirectoryTag, &keys[..])
            .expect("tag");
        img.encoder()
            .write_tag(Tag::ModelPixelScaleTag, &[30.0f64, 30.0, 0.0][..])
            .expect("tag");
        img.encoder()
            .write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 0.0, 90.0, 0.0][..])
            .expect("tag");
        let z: Vec<f32> = (0..12).map(|i| 100.0 + (i * 7 % 5) as f32).collect();
        img.write_data(&z).expect("data");
        let mut mask = enc.new_image::<colortype::Gray8>(4, 3).expect("mask");
        mask.encoder().write_tag(Tag::NewSubfileType, 4u32).expect("tag");
        let mut valid = [255u8; 12];
        valid[5] = 0;
        mask.write_data(&valid).expect("data");
    }
    let out = ok(&["info", s(&tif)]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("(1 voids)")
            && said.contains("nodata mask   an internal nodata mask (image 2 of the file): 1 samples voided"),
        "{said}"
    );
    let out = ok(&["info", s(&tif), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["dem"]["voids"], 1, "{v}");
}

/// A pipe is an input like a file (`tincull info <(gen)`): it gives its bytes once, so no look at its first bytes
/// may take them from the reader (a mesh piped in used to lose its first 4,096 bytes to that look), and what it holds
/// is told by those bytes as for a file (a hierarchy or a PVS file piped into `info` used to be read as a mesh).
#[cfg(unix)]
#[test]
fn inputs_are_read_from_pipes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("p.tch");
    let piped = |command: &str| {
        let out = Command::new("bash")
            .arg("-c")
            .arg(format!("\"$0\" {command}"))
            .arg(env!("CARGO_BIN_EXE_tincull"))
            .output()
            .expect("bash runs");
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "tincull {command} failed:\n{stderr}");
        String::from_utf8(out.stdout).expect("UTF-8 output")
    };
    let obj = mesh("jacksboro-2k.obj");
    let info: serde_json::Value =
        serde_json::from_str(&piped(&format!("info <(cat '{}') --json", s(&obj)))).expect("one JSON object");
    assert_eq!(info["import"]["vertices"], 2000, "{info}");
    piped(&format!("build <(cat '{}') -o '{}' -q", s(&obj), s(&tch)));
    let from_file = json(&["cull", s(&tch), "--eye", "0,0,2", "--above-ground", "--json"]);
    let from_pipe: serde_json::Value = serde_json::from_str(&piped(&format!(
        "cull <(cat '{}') --eye 0,0,2 --above-ground --json",
        s(&tch)
    )))
    .expect("one JSON object");
    assert_eq!(from_pipe["ranges"], from_file["ranges"]);
    assert!(
        from_file["ranges"].as_array().is_some_and(|r| !r.is_empty()),
        "{from_file}"
    );
    // `info` tells a piped hierarchy and a piped PVS file by their bytes, with their sizes; `build -o -` pipes into it.
    let of_file = json(&["info", s(&tch), "--json"]);
    for command in [
        format!("info <(cat '{}') --json", s(&tch)),
        format!("build '{}' -o - -q | \"$0\" info /dev/stdin --json", s(&obj)),
    ] {
        let of_pipe: serde_json::Value = serde_json::from_str(&piped(&command)).expect("one JSON object");
        for key in ["file_bytes", "nodes", "triangles", "visibility_bytes"] {
            assert_eq!(of_pipe[key], of_file[key], "{command}: {key}");
        }
    }
    let pvs = dir.path().join("p.pvs");
    ok(&["pvs", s(&tch), "--cell", "9000,9000,9500,9500", "-o", s(&pvs), "-q"]);
    let (of_file, of_pipe) = (
        json(&["info", s(&pvs), "--json"]),
        serde_json::from_str::<serde_json::Value>(&piped(&format!("info <(cat '{}') --json", s(&pvs))))
            .expect("one JSON object"),
    );
    assert!(of_file["cells"].as_array().is_some_and(|c| c.len() == 1), "{of_file}");
    assert_eq!(of_pipe["cells"], of_file["cells"]);
    // A piped hierarchy given where a mesh is read is named as one, as a file is.
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "\"$0\" build <(cat '{}') -o '{}'",
            s(&tch),
            s(&dir.path().join("x.tch"))
        ))
        .arg(env!("CARGO_BIN_EXE_tincull"))
        .output()
        .expect("bash runs");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("is a tincull hierarchy (.tch), not a mesh"), "{stderr}");
}

/// `cull` reports the safe culler's work units and occluder edges (JSON and text), so a user tuning `--work-budget`
/// sees when the budget binds; the other methods report none.
#[test]
fn cull_reports_the_work_it_spent_against_the_budget() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("j.tch");
    ok(&["build", s(&mesh("jacksboro-2k.obj")), "-o", s(&tch), "-q"]);
    let eye = ["--eye", "10000,12000,2", "--above-ground"];
    let free = json(&[&["cull", s(&tch)][..], &eye, &["--json"]].concat());
    let (work, edges) = (
        free["work"].as_u64().expect("work"),
        free["occluder_edges"].as_u64().expect("edges"),
    );
    assert!(work > 0 && work < 200_000 && edges > 0 && edges < work, "{free}");
    let said = String::from_utf8_lossy(&ok(&[&["cull", s(&tch)][..], &eye].concat()).stdout).into_owned();
    assert!(
        said.contains(&format!("{work} work units of 200000, {edges} occluder edges written")),
        "{said}"
    );
    // A budget of 5 units is spent exactly, and the text says so.
    let tight = json(&[&["cull", s(&tch)][..], &eye, &["--work-budget", "5", "--json"]].concat());
    assert_eq!(tight["work"], 5, "{tight}");
    let said = ok(&[&["cull", s(&tch)][..], &eye, &["--work-budget", "5"]].concat()).stdout;
    assert!(
        String::from_utf8_lossy(&said).contains("5 work units of 5 (the budget: spent)"),
        "{}",
        String::from_utf8_lossy(&said)
    );
    let thesis = json(&[&["cull", s(&tch)][..], &eye, &["--method", "thesis", "--json"]].concat());
    assert_eq!(
        (&thesis["work"], &thesis["occluder_edges"]),
        (&0.into(), &0.into()),
        "{thesis}"
    );
    let said = ok(&[&["cull", s(&tch)][..], &eye, &["--method", "thesis"]].concat()).stdout;
    assert!(!String::from_utf8_lossy(&said).contains("work units"));
}

/// `cull --above-ground` (and `eval --eyes --above-ground`) reads z as a height above the terrain: the same cull as
/// with the world z it reports, and an eye off the terrain is an error naming it.
#[test]
fn cull_above_ground() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("j.tch");
    ok(&["build", s(&mesh("jacksboro-2k.obj")), "-o", s(&tch), "-q"]);
    let rel = json(&["cull", s(&tch), "--eye", "10000,12000,2", "--above-ground", "--json"]);
    let eye: Vec<f64> = rel["eye"]
        .as_array()
        .expect("eye")
        .iter()
        .map(|v| v.as_f64().expect("number"))
        .collect();
    assert_eq!(&eye[..2], &[10000.0, 12000.0]);
    // Within the mesh's heights (236 .. 1076 m), 2 m up.
    assert!(eye[2] > 238.0 && eye[2] < 1078.0, "{eye:?}");
    let world = format!("{},{},{}", eye[0], eye[1], eye[2]);
    let abs = json(&["cull", s(&tch), "--eye", &world, "--json"]);
    assert_eq!(rel["ranges"], abs["ranges"]);
    fails_with(
        &["cull", s(&tch), "--eye", "-5000,0,2", "--above-ground"],
        "the eye (--eye) at x -5000, y 0 is outside the terrain's footprint",
    );
    // An eye below the ground is refused, naming it (its line in a file of eyes), by cull and eval alike; one on
    // the ground (0 m above it, as --above-ground reports it) is not.
    let on = json(&["cull", s(&tch), "--eye", "10000,12000,0", "--above-ground", "--json"]);
    let ground = on["eye"][2].as_f64().expect("z");
    ok(&["cull", s(&tch), "--eye", &format!("10000,12000,{ground}"), "--json"]);
    let below = format!("10000,12000,{}", ground - 0.01);
    fails_with(
        &["cull", s(&tch), "--eye", &below],
        "the eye (--eye) at x 10000, y 12000",
    );
    fails_with(
        &["cull", s(&tch), "--eye", &below],
        &format!(
            "0.010 m below the ground (at z {ground:.3} there): an eye below the ground sees none of the terrain (for \
             heights above the ground, give --above-ground)"
        ),
    );
    // Huge values are written short, not as hundreds of digits.
    fails_with(
        &["cull", s(&tch), "--eye", "10000,12000,-1e308"],
        &format!("z -1e308 is 1.0e308 m below the ground (at z {ground:.3} there)"),
    );
    fails_with(
        &["cull", s(&tch), "--eye", "10000,12000,-1e308", "--above-ground"],
        "must be 0 or more (an eye below the ground sees none of the terrain), got -1e308",
    );
    fails_with(
        &["cull", s(&tch), "--eye", "1e300,0,2", "--above-ground"],
        "the eye (--eye) at x 1e300, y 0 is outside the terrain's footprint",
    );
    let eyes = dir.path().join("eyes.txt");
    std::fs::write(&eyes, format!("# a path\n-5000,0,2\n{below}\n")).expect("eyes");
    let line = format!("eye 2 ({}:3)", eyes.display());
    fails_with(&["cull", s(&tch), "--eyes", s(&eyes)], &line);
    fails_with(&["eval", s(&tch), "--eyes", s(&eyes), "--no-safe-regions"], &line);
    // `eval --eyes` suggests --above-ground too, and takes it: the same scores as the world z it stands for.
    let stderr =
        String::from_utf8_lossy(&run(&["eval", s(&tch), "--eyes", s(&eyes), "--no-safe-regions"]).stderr).into_owned();
    assert!(
        stderr.contains("below the ground") && stderr.contains("give --above-ground"),
        "{stderr}"
    );
    let (relative, absolute) = (dir.path().join("rel.txt"), dir.path().join("abs.txt"));
    std::fs::write(&relative, "10000,12000,2\n").expect("eyes");
    std::fs::write(&absolute, format!("{world}\n")).expect("eyes");
    let score = |file: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "eval",
            s(&tch),
            "--eyes",
            s(file),
            "--no-safe-regions",
            "--no-per-triangle",
            "--json",
        ];
        args.extend_from_slice(extra);
        let mut v = json(&args);
        // The methods left out took no time to set up (the time of an empty branch was reported once).
        for skipped in ["per_triangle_setup_seconds", "safe_regions_setup_seconds"] {
            assert_eq!(v[skipped], 0.0, "{skipped}: {v}");
        }
        v["rows"]
            .as_array_mut()
            .expect("rows")
            .iter_mut()
            .for_each(|r| r["cull_ns"] = serde_json::Value::Null);
        v["rows"].clone()
    };
    assert_eq!(score(&relative, &["--above-ground"]), score(&absolute, &[]));
    // An eye 1e12 m away: the exact checker's tolerance (1e-9 of the distance) would be a kilometre there, and it
    // called half the terrain visible from it (found by a user's test): eval refuses it; cull takes it.
    let far = dir.path().join("far.txt");
    std::fs::write(&far, format!("{world}\n1e12,-1e12,500\n")).expect("eyes");
    fails_with(
        &["eval", s(&tch), "--eyes", s(&far), "--no-safe-regions"],
        &format!(
            "eye 2 ({}:2) at (1000000000000.000, -1000000000000.000, 500.000) lies 1e12 m from",
            far.display()
        ),
    );
    ok(&["cull", s(&tch), "--eyes", s(&far), "--json"]);
    fails_with(
        &[
            "eval",
            s(&tch),
            "--eyes",
            s(&eyes),
            "--above-ground",
            "--no-safe-regions",
        ],
        "eye 1 (",
    );
    fails_with(&["eval", s(&tch), "--above-ground"], "--eyes");
}

/// The full-resolution path (issue #18): a regular grid kept whole (every cell's four corners are cocircular, so
/// the Delaunay triangulation is degenerate everywhere) and at max error 0 builds, evaluates and culls, and the
/// build does not depend on the thread count.
#[test]
fn a_whole_regular_grid_builds_and_culls() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asc = dir.path().join("grid.asc");
    let (rows, cols) = (24, 31);
    let mut text =
        format!("ncols {cols}\nnrows {rows}\nxllcorner 500000\nyllcorner 4000000\ncellsize 30\nNODATA_value -9999\n");
    for r in 0..rows {
        // Ridges and flat runs: many samples lie exactly on the planes of their neighbours.
        let row: Vec<String> = (0..cols)
            .map(|c| format!("{}", ((r * 7 + c * 3) % 11).min(6) * 10 + (c / 8) * 40))
            .collect();
        text += &row.join(" ");
        text += "\n";
    }
    std::fs::write(&asc, text).expect("fixture");
    let whole = dir.path().join("whole.obj");
    let v = json(&["tin", s(&asc), "-o", s(&whole), "--keep-grid", "--json", "-q"]);
    assert_eq!(v["vertices"], rows * cols);
    // The same keys as a simplified TIN's report, null where nothing was simplified.
    assert!(v.get("simplify_seconds").is_some_and(|t| t.is_null()), "{v}");
    assert_eq!(v["triangles"], 2 * (rows - 1) * (cols - 1));
    let exact = dir.path().join("exact.obj");
    let e = json(&["tin", s(&asc), "-o", s(&exact), "--max-error", "0", "--json", "-q"]);
    assert!(e["vertices"].as_u64().expect("count") < (rows * cols) as u64);
    for mesh in [&whole, &exact] {
        let tch = dir.path().join("h.tch");
        let one = dir.path().join("one.tch");
        let b = json(&["build", s(mesh), "-o", s(&tch), "--json", "-q"]);
        assert_eq!(b["vertices"], json(&["info", s(mesh), "--json"])["vertices"]);
        let out = bin()
            .args(["build", s(mesh), "-o", s(&one), "-q"])
            .env("RAYON_NUM_THREADS", "1")
            .output()
            .expect("runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(
            std::fs::read(&tch).expect("written"),
            std::fs::read(&one).expect("written")
        );
        let c = json(&["cull", s(&tch), "--eye", "500450,4000300,400", "--json", "-q"]);
        let drawn = c["triangles_drawn"].as_u64().expect("triangles drawn");
        assert!(drawn <= b["triangles"].as_u64().expect("triangles"), "{c}");
        ok(&[
            "eval",
            s(&tch),
            "--viewpoints",
            "2",
            "--classes",
            "ground,high",
            "--no-per-triangle",
            "--json",
            "-q",
        ]);
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).expect("fixture");
        p
    };
    fails_with(&["info", "/no/such/file.obj"], "No such file");
    fails_with(&["info", s(&write("empty.obj", ""))], "empty.obj");
    fails_with(
        &["info", s(&write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"))],
        "range.obj:4",
    );
    fails_with(
        &["info", s(&write("nan.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\n"))],
        "nan.obj:2",
    );
    fails_with(
        &["info", s(&write("wall.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 5\n"))],
        "wall.obj",
    );
    fails_with(&["info", s(&write("cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1"))], "cut.obj:3");
    let nonmanifold = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\nf 1 2 3\nf 1 2 4\nf 1 2 5\n";
    fails_with(&["info", "--keep-faces", s(&write("nm.obj", nonmanifold))], "nm.obj");
    // A crack: vertex 5 on the edge of the first face at 50 m where that edge is at 0 m (a T-junction the faces only
    // touch at, so no overlap); named by the face's line and the vertex.
    let cracked = "v 0 0 0\nv 10 0 0\nv 5 10 0\nv 5 -10 0\nv 5 0 50\nf 1 2 3\nf 1 4 5\nf 5 4 2\n";
    fails_with(
        &["info", "--keep-faces", s(&write("crack.obj", cracked))],
        "crack.obj:6: vertex 5 lies on an edge of the face, not at one of its corners, at another height",
    );
    // Faces cut short: the vertices no face uses are dropped, with a warning naming the file.
    let cut = write("short.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\nf 1 2 3\n");
    let warned = String::from_utf8_lossy(&ok(&["info", "--keep-faces", s(&cut)]).stderr).into_owned();
    assert!(
        warned.contains("short.obj: dropped 2 vertices that no face uses"),
        "{warned}"
    );
    assert!(!warned.contains("line break"), "{warned}");
    // Cut within its last line, a file may still read (`10.` is a number, a face may have lost nothing): a file that
    // does not end with a line break, as every OBJ writer ends one, is named with a warning.
    let cut = write("cut10.obj", "v 0 0 0\nv 10 0 1\nv 0 10 2\nv 10 10 3.");
    let warned = String::from_utf8_lossy(&ok(&["info", s(&cut)]).stderr).into_owned();
    assert!(
        warned.contains("cut10.obj: the file does not end with a line break, as a file cut short would not"),
        "{warned}"
    );
    fails_with(
        &["info", s(&write("foreign.obj", "\u{0}\u{1}binary garbage\n"))],
        "foreign.obj",
    );
    fails_with(
        &["tin", "/no/such/dem.npy", "-o", "x.obj", "--vertices", "10"],
        "dem.npy",
    );
    fails_with(
        &["build", s(&mesh("jacksboro-2k.obj")), "-o", "x.tch", "--sectors", "2"],
        "sector",
    );
    fails_with(
        &[
            "horizon",
            s(&mesh("jacksboro-2k.obj")),
            "--sectors",
            "64",
            "--subsectors",
            "64",
        ],
        "1024",
    );
    // A grid whose samples are all void: the error names the file, whichever command reads it.
    let void = write(
        "void.asc",
        "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 30\nNODATA_value -9999\n\
         -9999 -9999 -9999\n-9999 -9999 -9999\n-9999 -9999 -9999\n",
    );
    fails_with(
        &["tin", s(&void), "-o", "x.obj", "--vertices", "10"],
        "void.asc: cannot triangulate",
    );
    fails_with(
        &["tin", s(&void), "-o", "x.obj", "--keep-grid"],
        "void.asc: cannot triangulate",
    );
    fails_with(&["info", s(&void)], "void.asc: cannot triangulate");
    fails_with(&["cull", "/no/such.tch", "--eye", "0,0,0"], "such.tch");
    // A device given as an input is refused, not read: `/dev/zero` read whole would take all memory.
    let tch = dir.path().join("j2k.tch");
    ok(&["build", s(&mesh("jacksboro-2k.obj")), "-o", s(&tch), "-q"]);
    for args in [
        vec!["info", "/dev/zero"],
        vec!["build", "/dev/zero", "-o", "x.tch"],
        vec!["cull", "/dev/zero", "--eye", "0,0,0"],
        vec!["cull", s(&tch), "--eyes", "/dev/zero"],
        vec!["eval", s(&tch), "--eyes", "/dev/zero"],
        vec![
            "build",
            s(&mesh("jacksboro-2k.obj")),
            "-o",
            "x.tch",
            "--config",
            "/dev/zero",
        ],
        vec!["tiles", "build", "/dev/zero", "--all"],
    ] {
        fails_with(&args, "/dev/zero: a character device, not a file");
    }
    fails_with(
        &["cull", s(&mesh("jacksboro-2k.obj")), "--eye", "0,0,0"],
        "jacksboro-2k.obj is an OBJ mesh, not a tincull hierarchy: build one with `tincull build",
    );
    // Every command that reads a hierarchy names the file of a damaged one.
    let damaged = tempfile::tempdir().expect("tempdir");
    let bad = damaged.path().join("bad.tch");
    let csv = damaged.path().join("map.csv");
    std::fs::write(&bad, b"TINCULL\x1a\x02\0\0\0").expect("write");
    for args in [
        vec!["cull", s(&bad), "--eye", "0,0,0"],
        vec!["eval", s(&bad)],
        vec!["export", s(&bad), "--export-json", "-"],
        vec!["pvs", s(&bad), "--check", "1"],
        vec!["failmap", s(&bad), "--cell-size", "10", "--csv", s(&csv)],
    ] {
        fails_with(&args, "bad.tch: truncated");
    }
    fails_with(&["cull", "x.tch", "--eye", "1,2"], "x,y,z");
    // Without a viewpoint, both ways of giving one are named; with both, they clash.
    fails_with(&["cull", "x.tch"], "<--eye <EYE>|--eyes <EYES>>");
    fails_with(
        &["cull", "x.tch", "--eye", "1,2,3", "--eyes", "e.txt"],
        "cannot be used with",
    );
}

#[test]
fn horizon_sweep_matches_the_oracle() {
    let v = json(&[
        "horizon",
        s(&mesh("jacksboro-2k.obj")),
        "--sectors",
        "8",
        "--subsectors",
        "2",
        "--verify",
        "--json",
    ]);
    assert_eq!(v["mismatches"], 0);
    assert_eq!(v["vertices"], 2000);
    assert_eq!(v["subsectors"], 2, "per sector, as everywhere");
    assert_eq!(v["total_subsectors"], 16);
}

#[test]
fn build_cull_export_eval_round_trip() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("j2k.tch");
    let report = json(&[
        "build",
        s(&mesh("jacksboro-2k.obj")),
        "-o",
        s(&tch),
        "--seeds",
        "20",
        "--json",
    ]);
    for key in [
        "horizon_seconds",
        "grouping_seconds",
        "orphan_passes_run",
        "orphans",
        "groups",
        "nodes",
        "levels",
        "top_level",
        "visibility_bytes",
    ] {
        assert!(report.get(key).is_some(), "build report lacks {key}");
    }
    let groups = report["groups"].as_u64().expect("groups");
    assert!(groups >= 1);
    assert_eq!(
        (report["seeds"].as_u64(), report["first_pass_crystals"].as_u64()),
        (Some(20), Some(20)),
        "20 seeds on 3,908 free triangles start 20 crystals"
    );
    // More seeds than triangles: the report says how many crystals could start.
    let many = dir.path().join("many.tch");
    let j2k = mesh("jacksboro-2k.obj");
    let args = ["build", s(&j2k), "-o", s(&many), "--seeds", "100000"];
    let r = json(&[&args[..], &["--json"]].concat());
    let started = r["first_pass_crystals"].as_u64().expect("first_pass_crystals");
    assert!(
        started <= r["triangles"].as_u64().expect("triangles") && started > 20,
        "{r}"
    );
    let text = String::from_utf8_lossy(&ok(&args).stdout).into_owned();
    assert!(
        text.contains(&format!("100000 seeds ({started} crystals started)")),
        "{text}"
    );
    if cfg!(target_os = "linux") {
        let peak = report["peak_memory_bytes"].as_u64().expect("peak memory on Linux");
        assert!((1 << 20..1 << 34).contains(&peak), "peak memory {peak} bytes");
    }

    let bbox = json(&["info", s(&mesh("jacksboro-2k.obj")), "--json"])["bbox"].clone();
    let (cx, cy) = (
        (bbox["min"][0].as_f64().expect("x") + bbox["max"][0].as_f64().expect("x")) / 2.0,
        (bbox["min"][1].as_f64().expect("y") + bbox["max"][1].as_f64().expect("y")) / 2.0,
    );
    let eye = format!("{cx},{cy},1000");
    let c = json(&["cull", s(&tch), "--eye", &eye, "--json"]);
    let triangles = report["triangles"].as_u64().expect("triangles");
    let drawn: u64 = c["ranges"]
        .as_array()
        .expect("ranges")
        .iter()
        .map(|r| r[1].as_u64().expect("end") - r[0].as_u64().expect("start"))
        .sum();
    assert_eq!(drawn, c["triangles_drawn"].as_u64().expect("drawn"));
    assert!(drawn <= triangles);
    let eyes = dir.path().join("eyes.txt");
    // Comments (whole lines and after an eye) and a byte-order mark (as some editors write) are skipped.
    std::fs::write(&eyes, format!("\u{feff}{eye}  # first\n# a comment\n{cx},{cy},5000\n")).expect("eyes");
    let lines = ok(&["cull", s(&tch), "--eyes", s(&eyes), "--json"]).stdout;
    assert_eq!(String::from_utf8_lossy(&lines).lines().count(), 2);
    let v = json(&[
        "eval",
        s(&tch),
        "--eyes",
        s(&eyes),
        "--no-safe-regions",
        "--no-per-triangle",
        "--json",
    ]);
    assert!(v["options"]["viewpoints"].is_null(), "--eyes has no classes: {v}");
    assert!(v["options"]["classes"].is_null(), "--eyes has no classes: {v}");
    assert!(
        v["options"]["eyes"].as_u64().is_some_and(|n| n > 0),
        "--eyes counted: {v}"
    );

    let (json_out, obj_out) = (dir.path().join("h.json"), dir.path().join("h.obj"));
    ok(&[
        "export",
        s(&tch),
        "--export-json",
        s(&json_out),
        "--export-obj",
        s(&obj_out),
    ]);
    let obj = std::fs::read_to_string(&obj_out).expect("obj");
    assert_eq!(obj.matches("\ng group_").count() as u64, groups);
    assert!(obj.contains("\ng orphans\n"));
    assert!(dir.path().join("h.mtl").exists());
    let h: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_out).expect("json")).expect("parses");
    assert_eq!(
        h["nodes"].as_array().expect("nodes").len() as u64,
        report["nodes"].as_u64().expect("nodes")
    );

    let csv = dir.path().join("e.csv");
    ok(&[
        "eval",
        s(&tch),
        "--viewpoints",
        "2",
        "--classes",
        "ground,sky",
        "--csv",
        s(&csv),
        "-q",
    ]);
    let csv = std::fs::read_to_string(&csv).expect("csv");
    assert!(csv.starts_with("method,class,viewpoints,"));
    for method in [
        "safe,ground",
        "safe_regions,sky",
        "thesis,ground",
        "per_triangle,sky",
        "frustum_only,all",
        "none,all",
    ] {
        assert!(csv.contains(method), "csv lacks {method}");
    }

    // Corruption of the file is detected.
    let mut bytes = std::fs::read(&tch).expect("tch");
    let last = bytes.len() - 1;
    bytes[last] ^= 0x55;
    let bad = dir.path().join("bad.tch");
    std::fs::write(&bad, &bytes).expect("bad");
    fails_with(&["cull", s(&bad), "--eye", &eye], "checksum");
    std::fs::write(&bad, &bytes[..bytes.len() / 2]).expect("bad");
    fails_with(&["export", s(&bad), "--export-json", s(&json_out)], "truncated");
}

#[test]
fn build_is_deterministic_across_threads_and_seeds() {
    let dir = tempfile::tempdir().expect("tempdir");
    let build = |name: &str, seed: &str, threads: &str| {
        let p = dir.path().join(name);
        let out = bin()
            .args([
                "build",
                s(&mesh("jacksboro-2k.obj")),
                "-o",
                s(&p),
                "--rng-seed",
                seed,
                "-q",
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .expect("runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        std::fs::read(p).expect("written")
    };
    let one = build("a.tch", "3", "1");
    let two = build("b.tch", "3", "2");
    assert!(one == two, "same seed, 1 vs 2 threads: different .tch files");
    assert!(build("c.tch", "4", "2") != one, "another seed should change the groups");
}

/// `-` names standard output for outputs; for an input, the error says how to read standard input.
#[test]
fn a_dash_input_points_to_dev_stdin() {
    fails_with(
        &["info", "-"],
        "-: no file of that name (standard input is read as /dev/stdin)",
    );
}

/// `--threads` sets the worker count, before or after the command, and changes no byte of the output.
#[test]
fn threads_sets_the_worker_count() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (a, b) = (dir.path().join("a.tch"), dir.path().join("b.tch"));
    let m = mesh("jacksboro-2k.obj");
    let one = json(&["--threads", "1", "build", s(&m), "-o", s(&a), "--json", "-q"]);
    assert_eq!(one["threads"], 1, "{one}");
    let three = json(&["build", s(&m), "-o", s(&b), "--threads", "3", "--json", "-q"]);
    assert_eq!(three["threads"], 3, "{three}");
    assert!(
        std::fs::read(&a).expect("written") == std::fs::read(&b).expect("written"),
        "1 vs 3 threads: different .tch files"
    );
    let c = dir.path().join("c.tch");
    fails_with(&["build", s(&m), "-o", s(&c), "--threads", "0"], "--threads");
    assert!(!c.exists());
    // The environment's count is read as --threads' default; one rayon would ignore is refused, not ignored.
    let with_env = |value: &str| {
        bin()
            .args(["build", s(&m), "-o", s(&c), "--json", "-q"])
            .env("RAYON_NUM_THREADS", value)
            .output()
            .expect("the binary runs")
    };
    let out = with_env("2");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["threads"], 2, "{v}");
    std::fs::remove_file(&c).expect("remove");
    // Spaces around the number, which rayon alone would ignore, and an empty variable, taken as unset.
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    for (value, threads) in [(" 3 ", 3), ("", cores)] {
        let out = with_env(value);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
        assert_eq!(v["threads"], threads, "RAYON_NUM_THREADS={value:?}: {v}");
        std::fs::remove_file(&c).expect("remove");
    }
    for (bad, message) in [
        ("abc", "not a number of worker threads"),
        ("-3", "not a number of worker threads"),
        ("1.5", "not a number of worker threads"),
        ("100000", "at most 65535 worker threads"),
    ] {
        let out = with_env(bad);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "RAYON_NUM_THREADS={bad}");
        assert!(
            stderr.contains(&format!("RAYON_NUM_THREADS={bad}: {message}")),
            "{stderr}"
        );
        assert!(!c.exists());
    }
    // Before and after the command: refused as clap refuses it twice on one side, not the second taken silently.
    let out = bin()
        .args(["--threads", "1", "build", s(&m), "-o", s(&c), "--threads=2"])
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--threads is given twice"), "{stderr}");
    assert!(!c.exists());
}

/// Byte-identical outputs at any thread count, on the 10k mesh (large enough for the parallel sorts, checks and
/// orders of `tin` and `crystal` to split their work) and through the DEM paths (simplification, the whole grid),
/// at 1, 3 and 5 threads on a 2-core machine (more threads than cores split the work differently again).
#[test]
fn outputs_are_identical_at_any_thread_count() {
    let dir = tempfile::tempdir().expect("tempdir");
    let dem = s(&shared_dem("N43W123.hgt")).to_string();
    let run_with = |threads: &str, args: &[&str], out: &str| {
        let p = dir.path().join(format!("{threads}-{out}"));
        let mut all: Vec<&str> = args.to_vec();
        all.extend(["-o", s(&p), "-q"]);
        let o = bin()
            .args(&all)
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .expect("runs");
        assert!(o.status.success(), "{all:?}: {}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(p).expect("written")
    };
    let j10k = s(&mesh("jacksboro-10k.obj")).to_string();
    let cases: [(&[&str], &str); 3] = [
        (&["build", &j10k, "--rng-seed", "7"], "b.tch"),
        (&["tin", &dem, "--vertices", "30000"], "t.obj"),
        (&["tin", &dem, "--keep-grid"], "g.obj"),
    ];
    for (args, out) in cases {
        let one = run_with("1", args, out);
        for threads in ["3", "5"] {
            assert!(
                run_with(threads, args, out) == one,
                "{args:?}: 1 vs {threads} threads differ"
            );
        }
    }
}

#[test]
fn parameters_come_from_toml_and_the_command_line_wins() {
    let dir = tempfile::tempdir().expect("tempdir");
    let toml = dir.path().join("p.toml");
    std::fs::write(&toml, "sectors = 8\nsubsectors = 2\nmin_group = 20\n").expect("toml");
    let tch = dir.path().join("p.tch");
    let v = json(&[
        "build",
        s(&mesh("jacksboro-2k.obj")),
        "-o",
        s(&tch),
        "--config",
        s(&toml),
        "--subsectors",
        "1",
        "--json",
    ]);
    assert_eq!(v["params"]["sectors"], 8);
    assert_eq!(v["params"]["subsectors"], 1);
    assert_eq!(v["params"]["crystal"]["min_group"], 20);
    std::fs::write(&toml, "sector = 8\n").expect("toml");
    fails_with(
        &[
            "build",
            s(&mesh("jacksboro-2k.obj")),
            "-o",
            s(&tch),
            "--config",
            s(&toml),
        ],
        "p.toml: invalid parameters: unknown key `sector`",
    );
}

#[test]
fn delaunay_is_the_same_in_every_process() {
    // An integer grid: every cell is cocircular, so only a deterministic triangulator gives identical output.
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = dir.path().join("grid.obj");
    let mut text = String::new();
    for i in 0..60 * 60 {
        text += &format!("v {} {} {}\n", i % 60, i / 60, (i * 7919) % 13);
    }
    std::fs::write(&obj, text).expect("grid");
    let hashes: Vec<Vec<u8>> = (0..3)
        .map(|i| {
            let p = dir.path().join(format!("g{i}.tch"));
            ok(&["build", s(&obj), "-o", s(&p), "--seeds", "10", "-q"]);
            std::fs::read(p).expect("written")
        })
        .collect();
    assert!(hashes.windows(2).all(|w| w[0] == w[1]));
}

/// `../shared/dem` (CI has it; a missing directory fails the test).
fn shared_dem(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/dem");
    assert!(dir.is_dir(), "{} is missing: the GeoTIFF tests need it", dir.display());
    dir.join(name)
}

#[test]
fn geotiff_input_in_tin_info_and_mesh_commands() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let tif = shared_dem("N50E008_deflate.tif");
    let obj = tmp.path().join("n50.obj");
    let v = json(&["tin", s(&tif), "-o", s(&obj), "--vertices", "500", "--json", "--quiet"]);
    assert_eq!(v["vertices"], 500);
    assert_eq!(v["voids"], 50);
    // The same TIN as from the .hgt twin.
    let hgt_obj = tmp.path().join("n50-hgt.obj");
    ok(&[
        "tin",
        s(&shared_dem("N50E008.hgt")),
        "-o",
        s(&hgt_obj),
        "--vertices",
        "500",
        "--quiet",
    ]);
    assert_eq!(std::fs::read(&obj).expect("obj"), std::fs::read(&hgt_obj).expect("obj"));
    // info on a GeoTIFF: the grid and the CRS, then the mesh it simplifies to.
    let i = json(&[
        "info",
        s(&shared_dem("dfw_srtm.tif")),
        "--dem-vertices",
        "800",
        "--json",
        "--quiet",
    ]);
    assert_eq!(i["vertices"], 800);
    assert_eq!(i["dem"]["rows"], 359);
    assert_eq!(i["dem"]["geotiff"]["epsg"], 4326);
    assert_eq!(i["dem"]["geotiff"]["crs_kind"], "geographic");
    let text =
        String::from_utf8_lossy(&ok(&["info", s(&shared_dem("crater_lake_utm.tif")), "--dem-vertices", "300"]).stdout)
            .into_owned();
    assert!(text.contains("EPSG:26910 (projected, metres)"), "{text}");
    // A mesh command on a DEM.
    let tch = tmp.path().join("crater.tch");
    ok(&[
        "build",
        s(&shared_dem("crater_lake_utm.tif")),
        "--dem-vertices",
        "400",
        "-o",
        s(&tch),
        "--quiet",
    ]);
    assert!(tch.is_file());
    // A broken GeoTIFF: an error naming the file, no panic.
    let bad = tmp.path().join("bad.tif");
    std::fs::write(&bad, b"II*\0\x08\0\0\0garbage").expect("write");
    fails_with(&["tin", s(&bad), "-o", s(&obj), "--vertices", "10"], "bad.tif");
}

#[test]
fn export_gltf_writes_glb_and_gltf_with_bin() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let tch = tmp.path().join("j2k.tch");
    ok(&["build", s(&mesh("jacksboro-2k.obj")), "-o", s(&tch), "--quiet"]);
    let glb = tmp.path().join("j2k.glb");
    let gltf = tmp.path().join("j2k.gltf");
    ok(&["export", s(&tch), "--gltf", s(&glb), "--quiet"]);
    ok(&["export", s(&tch), "--gltf", s(&gltf), "--quiet"]);
    let bytes = std::fs::read(&glb).expect("glb");
    assert_eq!(&bytes[..4], b"glTF");
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&gltf).expect("gltf")).expect("JSON");
    assert_eq!(doc["buffers"][0]["uri"], "j2k.bin");
    assert!(tmp.path().join("j2k.bin").is_file());
    assert_eq!(doc["scenes"][0]["extras"]["tincull"]["version"], 1);
}

#[test]
fn messages_name_the_flag_at_fault() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("s.obj");
    fails_with(
        &["synth", "-o", s(&out), "--vertices", "2147483648"],
        "not enough memory",
    );
    fails_with(
        &["synth", "-o", s(&out), "--extent", "1e-300"],
        "too small for 10000 vertices",
    );
    assert!(!out.exists());
    let asc = common::small_asc(dir.path(), "g.asc");
    fails_with(&["tin", s(&asc), "--vertices", "1", "-o", s(&out)], "--vertices");
    let file = dir.path().join("afile");
    std::fs::write(&file, "x").expect("file");
    fails_with(&["demo", "--out-dir", s(&file)], "is not a directory");
    fails_with(&["pvs", "x.tch"], "--grid");
    // A negative number is the option's value, refused by its own check (not an unknown flag with a tip to write
    // `-- -1`), in subcommands of subcommands too.
    for (args, needle) in [
        (
            vec!["tin", s(&asc), "--max-error", "-1", "-o", s(&out)],
            "'-1' for '--max-error <M>': -1: the error bound must be finite and non-negative",
        ),
        (
            vec!["tin", s(&asc), "--max-error", "inf", "-o", s(&out)],
            "'inf' for '--max-error <M>'",
        ),
        (
            // A scale that carries the heights out of range is named with the height.
            vec!["tin", s(&asc), "--vertices", "5", "--z-scale", "1e308", "-o", s(&out)],
            "(the stored value times the z scale 1e308)",
        ),
        (
            vec!["tin", s(&asc), "--vertices", "5", "--z-scale", "1e30", "-o", s(&out)],
            "(the stored value times the z scale 1e30) is outside the coordinates",
        ),
        (
            vec!["tin", s(&asc), "--vertices", "-5", "-o", s(&out)],
            "'-5' for '--vertices",
        ),
        (
            vec!["tiles", "plan", s(&asc), "--tile", "-5", "-o", s(&out)],
            "'-5' for '--tile",
        ),
    ] {
        fails_with(&args, needle);
        let stderr = String::from_utf8_lossy(&run(&args).stderr).into_owned();
        assert!(!stderr.contains("-- -"), "{stderr}");
    }
    assert!(!out.exists());
}

/// Builds the hierarchy of the bundled 2k mesh into `dir` (quietly) and returns its path.
fn build_2k(dir: &Path) -> PathBuf {
    let tch = dir.join("j2k.tch");
    ok(&["build", s(&mesh("jacksboro-2k.obj")), "-o", s(&tch), "-q"]);
    tch
}

/// Options that cannot mean what they say are errors naming them: a viewpoint class given twice, `--eyes` with the
/// seeded viewpoints' options, a failure map none of whose cells lies on the terrain, outputs that standard output
/// cannot take (saying why).
#[test]
fn contradictory_or_empty_options_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = build_2k(dir.path());
    fails_with(
        &["eval", s(&tch), "--viewpoints", "1", "--classes", "ground,ground"],
        "--classes: `ground` is given twice",
    );
    let eyes = dir.path().join("eyes.txt");
    std::fs::write(&eyes, "1000,1000,900\n").expect("eyes");
    fails_with(
        &["eval", s(&tch), "--eyes", s(&eyes), "--classes", "ground"],
        "--classes",
    );
    fails_with(
        &["eval", s(&tch), "--eyes", s(&eyes), "--viewpoints", "3"],
        "--viewpoints",
    );
    fails_with(
        &["eval", s(&tch), "--eyes", s(&eyes), "--view-seed", "5"],
        "at 360° it has nothing to seed",
    );
    fails_with(
        &["eval", s(&tch), "--above-ground", "--viewpoints", "1"],
        "without --eyes the viewpoint classes set their own heights",
    );
    let help = String::from_utf8_lossy(&ok(&["eval", "--help"]).stdout).into_owned();
    assert!(help.contains("not with --classes or --viewpoints"), "{help}");
    // More viewpoints than a run could score: refused, not a capacity overflow (a panic) or an aborted allocation.
    fails_with(
        &["eval", s(&tch), "--viewpoints", "18446744073709551615"],
        "--viewpoints 18446744073709551615: at most 1000000 per class",
    );
    fails_with(
        &["stress", s(&mesh("jacksboro-2k.obj")), "--viewpoints", "0"],
        "--viewpoints must be at least 1",
    );
    fails_with(
        &[
            "stress",
            s(&mesh("jacksboro-2k.obj")),
            "--viewpoints",
            "18446744073709551615",
        ],
        "at most 1000000 per class",
    );
    // A failure map of too many cells says how many compactly (not in 300 digits).
    fails_with(
        &["failmap", s(&tch), "--cell-size", "1e-300", "--json"],
        "a 1e-300 m cell gives 2.994297e304 x 3.18190",
    );
    // A binary file given as the eyes: said to be one, naming it.
    fails_with(
        &["cull", s(&tch), "--eyes", s(&tch)],
        "j2k.tch: a binary file, not a text file of eye positions",
    );

    // Eyes from which nothing is hidden (10,000 km up, the exact checker's reach): no mean of the occlusion captured
    // (it printed the empty sum's "-0.000").
    let png = dir.path().join("high.png");
    let o = ok(&[
        "failmap",
        s(&tch),
        "--cell-size",
        "10000",
        "--eye-height",
        "1e7",
        "-o",
        s(&png),
    ]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        text.contains("occlusion captured none (no cell hides any triangle)"),
        "{text}"
    );
    // Its JSON names its input and outputs, as every command's does.
    let v = json(&[
        "failmap",
        s(&tch),
        "--cell-size",
        "10000",
        "--eye-height",
        "1e7",
        "-o",
        s(&png),
        "--json",
    ]);
    assert_eq!(
        (v["hierarchy"].as_str(), v["output"].as_str()),
        (Some(s(&tch)), Some(s(&png))),
        "{v}"
    );
    assert!(v["csv"].is_null(), "{v}");

    let v = String::from_utf8_lossy(&run(&["failmap", s(&tch), "--cell-size", "1e9", "--json"]).stdout).into_owned();
    assert!(v.is_empty(), "{v}");
    fails_with(
        &["failmap", s(&tch), "--cell-size", "1e9", "--json"],
        "--cell-size 1e9: the centre of none of the 1 x 1 cells lies on the terrain",
    );

    let obj = dir.path().join("g.obj");
    fails_with(
        &["export", s(&tch), "--export-obj", "-"],
        "--export-obj -: the OBJ is written with its materials (.mtl) beside it",
    );
    fails_with(
        &["export", s(&tch), "--export-gltf", "-"],
        "--export-gltf -: glTF is written as a binary .glb",
    );
    fails_with(
        &[
            "build",
            s(&mesh("jacksboro-2k.obj")),
            "-o",
            s(&tch),
            "--export-obj",
            "-",
        ],
        "give a file name",
    );
    assert!(!obj.exists());
}

/// A file of the wrong kind given to a command is named for what it is, with what to do instead.
#[test]
fn files_of_the_wrong_kind_say_what_they_are() {
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = mesh("jacksboro-2k.obj");
    for args in [
        vec!["cull", s(&obj), "--eye", "1,1,1"],
        vec!["eval", s(&obj)],
        vec!["export", s(&obj), "--export-json", "-"],
        vec!["failmap", s(&obj), "--cell-size", "100", "--json"],
    ] {
        fails_with(
            &args,
            "jacksboro-2k.obj is an OBJ mesh, not a tincull hierarchy: build one with `tincull build",
        );
    }
    // An OBJ named .tch, by its content.
    let fake = dir.path().join("t.tch");
    std::fs::copy(&obj, &fake).expect("copy");
    fails_with(
        &["info", s(&fake)],
        "t.tch holds OBJ text (a mesh), not a tincull hierarchy",
    );
    fails_with(
        &["cull", s(&fake), "--eye", "1,1,1"],
        "rename it to .obj, then build a hierarchy with `tincull build MESH.obj -o MESH.tch`",
    );
    // A DEM grid.
    let npy = dir.path().join("g.npy");
    ok(&["synth", "-o", s(&npy), "--vertices", "400", "-q"]);
    fails_with(
        &["cull", s(&npy), "--eye", "1,1,1"],
        "g.npy is a DEM grid, not a tincull hierarchy",
    );
    // A PVS file (its magic number) to `info`, to a command that reads a hierarchy and to one that reads a mesh.
    let pvs = dir.path().join("g.pvs");
    let mut bytes = b"TINCPVS\x1a".to_vec();
    bytes.extend_from_slice(&[0; 40]);
    std::fs::write(&pvs, &bytes).expect("pvs");
    fails_with(&["info", s(&pvs)], "g.pvs: not a readable PVS file:");
    fails_with(
        &["info", s(&pvs), "--dem-vertices", "100"],
        "g.pvs: --dem-vertices 100 applies to a DEM grid input; a PVS file (.pvs) holds no mesh",
    );
    fails_with(
        &["cull", s(&pvs), "--eye", "1,1,1"],
        "g.pvs is a tincull PVS file (written by `tincull pvs -o`), not a hierarchy: this command reads the .tch written",
    );
    fails_with(&["stress", s(&pvs)], "g.pvs is a tincull PVS file");
    // JSON: a grid's sidecar names its grid; other JSON (a hierarchy's export) is named as JSON, not read as OBJ.
    let sidecar = dir.path().join("g.json");
    fails_with(
        &["info", s(&sidecar)],
        &format!("g.json is the JSON sidecar of the grid {} (give that file", s(&npy)),
    );
    let exported = dir.path().join("h.json");
    std::fs::write(&exported, "\n  {\"sectors\": 16, \"nodes\": []}\n").expect("json");
    for args in [vec!["info", s(&exported)], vec!["build", s(&exported), "-o", "x.tch"]] {
        fails_with(
            &args,
            "h.json is JSON (such as a hierarchy's `export --export-json` or a tiles plan), not a terrain",
        );
    }
    fails_with(
        &["cull", s(&exported), "--eye", "1,1,1"],
        "h.json is JSON (such as a hierarchy's `export --export-json` or a tiles plan), not a tincull hierarchy",
    );
}

/// A `.tch` whose length field is corrupt says that the file is truncated or corrupt and what its header declares.
#[test]
fn a_corrupt_length_field_is_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = build_2k(dir.path());
    let mut bytes = std::fs::read(&tch).expect("tch");
    let len = bytes.len();
    bytes[12..20].copy_from_slice(&1_095_216_736_226u64.to_le_bytes());
    let bad = dir.path().join("bad.tch");
    std::fs::write(&bad, &bytes).expect("bad");
    fails_with(
        &["info", s(&bad)],
        &format!(
            "bad.tch: truncated or corrupt hierarchy file: its header declares {} bytes, the file has {len}",
            1_095_216_736_226u64 + 24
        ),
    );
}

/// DEM readers: `--band` refused for every format but GeoTIFF (naming the file and the flag), a sidecar's bad spacing
/// in plain words, sample positions 1-based "row R, column C" whatever the check, and a bad `--dem-vertices` naming
/// the file.
#[test]
fn dem_messages_name_the_file_flag_and_sample() {
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("g.npy");
    ok(&["synth", "-o", s(&npy), "--vertices", "400", "-q"]);
    let out = dir.path().join("x.obj");
    for band in ["2", "1", "0"] {
        fails_with(
            &["tin", s(&npy), "--vertices", "100", "--band", band, "-o", s(&out)],
            &format!("g.npy: --band {band}: a .npy grid has one band"),
        );
    }
    fails_with(&["info", s(&npy), "--band", "2"], "g.npy: --band 2");
    let asc = common::small_asc(dir.path(), "g.asc");
    fails_with(
        &["tin", s(&asc), "--keep-grid", "--band", "1", "-o", s(&out)],
        "g.asc: --band 1: a .asc grid has one band",
    );
    fails_with(
        &["info", s(&npy), "--dem-vertices", "0"],
        "g.npy: --dem-vertices must be at least 3 and fit in 32 bits (at most 4294967295), got 0",
    );
    assert!(!out.exists());

    // The sidecar's spacing in plain words, naming the sidecar.
    let sidecar = dir.path().join("g.json");
    let text = std::fs::read_to_string(&sidecar).expect("sidecar");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let (rows, cols) = (v["rows"].as_u64().expect("rows"), v["cols"].as_u64().expect("cols"));
    v["spacing_x_m"] = serde_json::json!(-1);
    std::fs::write(&sidecar, v.to_string()).expect("sidecar");
    fails_with(&["info", s(&npy)], "g.json: spacing_x_m is -1, must be positive");
    let stderr = String::from_utf8_lossy(&run(&["info", s(&npy)]).stderr).into_owned();
    assert!(!stderr.contains("Some("), "{stderr}");
    std::fs::write(&sidecar, &text).expect("sidecar");

    // An infinite last sample and a first one too large: both 1-based, as row R, column C.
    let good = std::fs::read(&npy).expect("npy");
    let n = good.len();
    let mut bytes = good.clone();
    bytes[n - 8..].copy_from_slice(&f64::INFINITY.to_le_bytes());
    std::fs::write(&npy, &bytes).expect("npy");
    fails_with(
        &["info", s(&npy)],
        &format!("g.npy: row {rows}, column {cols} (1-based, row 1 north): the height is infinite"),
    );
    let mut bytes = good.clone();
    let first = n - (rows * cols * 8) as usize;
    bytes[first..first + 8].copy_from_slice(&1e200f64.to_le_bytes());
    std::fs::write(&npy, &bytes).expect("npy");
    fails_with(
        &["info", s(&npy)],
        "g.npy: row 1, column 1 (1-based, row 1 north): height 1e200",
    );
}

/// Huge numbers in messages are short, counts in human text agree with their nouns, and the help says what
/// combined options mean and which `--config` keys are read.
#[test]
fn messages_and_help_read_well() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("s.obj");
    let o = run(&["synth", "-o", s(&out), "--relief", "1e308"]);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success() && stderr.contains("got 1e308"), "{stderr}");
    assert!(stderr.len() < 200, "{stderr}");
    fails_with(
        &["cull", "x.tch", "--eye", "1,2,3", "--fov", "1e300"],
        "--fov 1e300: the field of view",
    );
    fails_with(
        &["synth", "-o", s(&out), "--vertices", "3"],
        "'3' for '--vertices <VERTICES>': \"3\": a synthetic terrain has 4 to 2^31 vertices",
    );
    // Range errors name their flag.
    fails_with(
        &["synth", "-o", s(&out), "--relief", "1e-30"],
        "relief (--relief) must be 0, or at least 1 µm and below 1e12 m, got 1e-30",
    );
    fails_with(
        &["horizon", s(&mesh("jacksboro-2k.obj")), "--sectors", "3"],
        "--sectors: sectors = 3: at least 4 sectors are needed",
    );
    fails_with(
        &["horizon", s(&mesh("jacksboro-2k.obj")), "--subsectors", "0"],
        "--subsectors: subsectors = 0",
    );
    let asc = common::small_asc(dir.path(), "g.asc");
    fails_with(
        &["tin", s(&asc), "--vertices", "99999999999", "-o", s(&out)],
        "the vertex budget (--vertices) must fit in 32 bits (at most 4294967295), got 99999999999",
    );
    fails_with(
        &["info", s(&asc), "--dem-vertices", "99999999999"],
        "--dem-vertices must be at least 3 and fit in 32 bits (at most 4294967295), got 99999999999",
    );
    assert!(!out.exists());

    let tch = build_2k(dir.path());
    let text = String::from_utf8_lossy(&ok(&["info", s(&tch)]).stdout).into_owned();
    for wrong in [" 1 roots", " 1 leaves", " 1 nodes", " 1 faces", " 1 ranges"] {
        assert!(!text.contains(wrong), "{text}");
    }
    assert!(text.contains(" roots") || text.contains(" 1 root,"), "{text}");

    let help = String::from_utf8_lossy(&ok(&["tin", "--help"]).stdout).into_owned();
    assert!(help.contains("at whichever is reached first"), "{help}");
    let help = String::from_utf8_lossy(&ok(&["build", "--help"]).stdout).into_owned();
    for key in ["orphan_passes", "max_expanse", "cell_size", "max_bytes", "not read"] {
        assert!(help.contains(key), "{key}: {help}");
    }
    let config = dir.path().join("p.toml");
    let build_with = |text: &str, needle: &str| {
        std::fs::write(&config, text).expect("config");
        fails_with(
            &[
                "build",
                s(&mesh("jacksboro-2k.obj")),
                "-o",
                s(&tch),
                "--config",
                s(&config),
            ],
            needle,
        );
    };
    build_with("keep_faces = true\n", "keep_faces");
    // A crystal key in the file with a quadtree grouping is named as the key it is, in its file.
    build_with(
        "grouping = \"quadtree\"\nseeds = 5\n",
        &format!("`seeds` (in {}) applies to the crystal grouping", config.display()),
    );
    // A grouping the file misspells (as the JSON of another version might write it) is named in its file.
    build_with(
        "grouping = \"Crystal\"\n",
        &format!("`grouping` (in {}): unknown grouping \"Crystal\"", config.display()),
    );
    // The command line wins over the file: `--depth` replaces the file's `cell_size` (both set the finest level), and
    // the report names the grouping and only its own parameters, as the options name them.
    std::fs::write(&config, "grouping = \"quadtree\"\ncell_size = 500\n").expect("config");
    let mesh2k = mesh("jacksboro-2k.obj");
    let args = ["build", s(&mesh2k), "-o", s(&tch), "--config", s(&config), "--json"];
    let v = json(&[&args[..], &["--depth", "2"]].concat());
    assert_eq!(v["params"]["grouping"], "quadtree", "{v}");
    assert_eq!(v["params"]["quadtree"]["depth"], 2, "{v}");
    assert!(
        v["params"]["quadtree"]["cell_size"].is_null() && v["params"]["crystal"].is_null(),
        "{v}"
    );
    let v = json(&args);
    assert_eq!(v["params"]["quadtree"]["cell_size"], 500.0, "{v}");
    build_with(
        "grouping = \"quadtree\"\ndepth = 2\ncell_size = 300\n",
        "(`depth` and `cell_size` in --config) both set the finest level",
    );
}

/// `info FILE.tch` checks the hierarchy's mesh as a height field, as `info MESH` does: a `.tch` whose mesh is not one
/// (written by another tool: its structure loads) is reported, with the violations in `--json`; `eval`, `failmap` and
/// `pvs --check` refuse it naming the file.
#[test]
fn info_checks_a_hierarchys_mesh_as_a_height_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = build_2k(dir.path());
    let text = String::from_utf8_lossy(&ok(&["info", s(&tch)]).stdout).into_owned();
    assert!(text.contains("height field  yes"), "{text}");
    assert_eq!(json(&["info", s(&tch), "--json"])["height_field"], true);

    // Two vertices at one x,y: a vertical wall.
    let mut h = cull::Hierarchy::load(&tch).expect("loads");
    let [x, y, _] = h.mesh.positions[1];
    h.mesh.positions[0][0] = x;
    h.mesh.positions[0][1] = y;
    let bad = dir.path().join("wall.tch");
    std::fs::write(&bad, h.to_bytes().expect("encodes")).expect("write");
    let text = String::from_utf8_lossy(&ok(&["info", s(&bad)]).stdout).into_owned();
    assert!(text.contains("height field  NO"), "{text}");
    let v = json(&["info", s(&bad), "--json", "-q"]);
    assert_eq!(v["height_field"], false);
    // The commands that need the exact checker refuse it naming the file (they named neither file nor cause).
    let needle = format!("{}: the hierarchy's mesh is not a valid terrain mesh", bad.display());
    fails_with(
        &[
            "eval",
            s(&bad),
            "--viewpoints",
            "1",
            "--classes",
            "ground",
            "--no-safe-regions",
        ],
        &needle,
    );
    fails_with(
        &[
            "failmap",
            s(&bad),
            "--cell-size",
            "500",
            "-o",
            s(&dir.path().join("map.png")),
        ],
        &needle,
    );
    fails_with(&["pvs", s(&bad), "--check", "1"], &needle);
}

#[test]
fn demo_refuses_dash_as_its_out_dir() {
    // Run in a scratch directory: a demo that took `-` as a directory name would write there.
    let dir = tempfile::tempdir().expect("tempdir");
    let m = mesh("jacksboro-2k.obj");
    let out = bin()
        .args(["demo", s(&m), "--out-dir", "-", "--viewpoints", "1", "-q"])
        .current_dir(dir.path())
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--out-dir -: the demo writes several files") && stderr.contains("give a directory name"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).expect("list").count(),
        0,
        "nothing created"
    );
    // A dangling symbolic link is named as one (it said "cannot create it: File exists").
    #[cfg(unix)]
    {
        let link = dir.path().join("out");
        std::os::unix::fs::symlink(dir.path().join("nowhere"), &link).expect("symlink");
        fails_with(
            &["demo", s(&m), "--out-dir", s(&link), "--viewpoints", "1", "-q"],
            "a symbolic link to nothing (its target does not exist); give a directory",
        );
        assert!(!dir.path().join("nowhere").exists());
    }
}

/// `view` checks what it would write and the method before a window opens: a screenshot over the input (which once
/// replaced the hierarchy by a PNG), of another format or into a missing folder, `--screenshot-after` alone, and a
/// method the hierarchy's grouping cannot take (as `render` refuses it) and `--no-regions` where `build` would refuse
/// it are errors, and nothing is written.
#[test]
fn view_checks_its_screenshot_and_method_before_opening_a_window() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("h.tch");
    ok(&["build", s(&mesh("jacksboro-2k.obj")), "-o", s(&tch), "-q"]);
    let before = std::fs::read(&tch).expect("hierarchy");
    fails_with(&["view", s(&tch), "--screenshot", s(&tch)], "h.tch");
    let typo = dir.path().join("shot.tch");
    fails_with(&["view", s(&tch), "--screenshot", s(&typo)], "name it .png");
    let missing = dir.path().join("no/shot.png");
    fails_with(&["view", s(&tch), "--screenshot", s(&missing)], "does not exist");
    fails_with(
        &["view", s(&tch), "--screenshot-after", "3"],
        "--screenshot-after 3 applies to --screenshot",
    );
    fails_with(&["view", s(&tch), "--method", "stewart"], "needs a quadtree hierarchy");
    fails_with(
        &["view", s(&mesh("jacksboro-2k.obj")), "--method", "stewart"],
        "needs a quadtree hierarchy",
    );
    fails_with(&["view", s(&tch), "--pvs-cell-size", "0"], "at least 1 m");
    // The side panel's build parameters are refused as `build` refuses them (the panel clamped them, and a rebuild
    // with too many subsectors failed inside the window only).
    fails_with(&["view", s(&tch), "--sectors", "3"], "at least 4 sectors are needed");
    fails_with(
        &["view", s(&tch), "--min-group", "0"],
        "`min_group`: must be at least 1",
    );
    fails_with(
        &["view", s(&mesh("jacksboro-2k.obj")), "--max-expanse", "-1"],
        "`max_expanse`: must be a positive fraction",
    );
    fails_with(
        &["view", s(&mesh("jacksboro-2k.obj")), "--sectors", "2000"],
        "exceeds the limit",
    );
    // Without regions a rebuild can only make a quadtree, and takes no horizon parameters.
    let no_regions = "--no-regions needs --grouping quadtree";
    fails_with(&["view", s(&tch), "--no-regions"], no_regions);
    fails_with(&["view", s(&mesh("jacksboro-2k.obj")), "--no-regions"], no_regions);
    fails_with(
        &[
            "view",
            s(&tch),
            "--no-regions",
            "--grouping",
            "quadtree",
            "--sectors",
            "8",
        ],
        "--no-regions computes no horizons",
    );
    fails_with(
        &["view", s(&mesh("jacksboro-2k.obj")), "--truth"],
        "a mesh has no culler until it is built: add --rebuild",
    );
    // Without a display: said plainly, once the arguments are checked.
    let without_display = |args: &[&str]| {
        let out = bin()
            .arg("view")
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("runs");
        assert!(!out.status.success(), "{args:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let shot = dir.path().join("shot.png");
    let err = without_display(&[s(&tch), "--screenshot", s(&shot)]);
    assert!(
        err.contains("no display to open the viewer's window on") && !err.contains(".rs:"),
        "{err}"
    );
    assert!(!shot.exists());
    // The culler's flags are checked before the display too.
    let err = without_display(&[s(&tch), "--columns", "3"]);
    assert!(
        err.contains("--columns must be a power of two") && !err.contains("no display"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(&tch).expect("hierarchy"),
        before,
        "the input is untouched"
    );
    assert!(!typo.exists() && !missing.exists());
}

/// `stress` names the file and the case when one of its cases fails on a mesh that builds (a square of 1e-30 m, whose
/// moved copies are degenerate), and a `--dem-dir` that is a file as such.
#[test]
fn stress_errors_name_the_file_and_the_case() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tiny = dir.path().join("tiny.obj");
    std::fs::write(&tiny, "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nv 1e-30 1e-30 1\n").expect("fixture");
    let out = run(&["stress", s(&tiny), "--quick", "--viewpoints", "1", "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("{}: stress case `", tiny.display())),
        "{stderr}"
    );
    fails_with(
        &["stress", s(&mesh("jacksboro-2k.obj")), "--dem-dir", s(&tiny), "--json"],
        "tiny.obj: not a folder (--dem-dir names the folder of the DEMs)",
    );
}
