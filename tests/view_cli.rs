//! End-to-end test of `tincull view`: the interactive viewer on a plain OBJ mesh under a virtual X server
//! (`xvfb-run`), building the hierarchy in the background with the real pipeline (`--rebuild`), computing the ground
//! truth (`--truth`), and writing a screenshot taken through egui's screenshot request.
//!
//! Without `xvfb-run` or a GPU the test prints a SKIP notice and passes, unless `TINCULL_REQUIRE_GPU` is set.

use std::path::PathBuf;
use std::process::Command;

fn find_program(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| p.is_file())
}

fn skip(why: &str) {
    if viewer::gpu_required() {
        panic!("TINCULL_REQUIRE_GPU is set but {why}");
    }
    eprintln!("SKIP: {why}; viewer test not run (set TINCULL_REQUIRE_GPU=1 to make this an error)");
}

/// Runs `tincull view INPUT ARGS --screenshot SHOT` under `xvfb-run`; its standard output, or `None` after the
/// SKIP notice when there is no display or GPU.
fn view(input: &std::path::Path, args: &[&str], shot: &std::path::Path) -> Option<String> {
    let Some(xvfb_run) = find_program("xvfb-run") else {
        skip("xvfb-run is not installed");
        return None;
    };
    let out = Command::new(xvfb_run)
        .args([
            "-a",
            "-s",
            "-screen 0 1280x1024x24",
            env!("CARGO_BIN_EXE_tincull"),
            "view",
        ])
        .arg(input)
        .args(args)
        .arg("--screenshot")
        .arg(shot)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        // Only a missing display or GPU is a reason to skip; any other failure is a failure.
        if stderr.contains("viewer window")
            || stderr.contains("no display")
            || stderr.contains("no GPU adapter")
            || stderr.contains("xvfb-run")
        {
            skip(&format!(
                "the viewer could not open a window ({}): {stderr}",
                out.status
            ));
            return None;
        }
        panic!("tincull view failed ({}):\n{stdout}\n{stderr}", out.status);
    }
    Some(stdout.into_owned())
}

fn bundled(name: &str) -> PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(name)
}

#[test]
fn view_rebuilds_an_obj_and_shows_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    // The view where the truth once counted what lies behind the camera as false culls (59 of them).
    let obj = bundled("jacksboro-2k.obj");
    let shot = dir.path().join("shot.png");
    let Some(stdout) = view(&obj, &["--rebuild", "--truth", "--size", "1000x700"], &shot) else {
        return;
    };
    assert!(stdout.contains("built the hierarchy 1 time;"), "{stdout}");
    assert!(!stdout.contains("without regions"), "{stdout}");
    assert!(stdout.contains("ground truth:"), "{stdout}");
    // The default culler is safe, and the truth of the default 90° view counts only what lies in it: what the view
    // leaves out is not a false cull (it once counted those behind the camera).
    assert!(stdout.contains(" 0 false culls"), "{stdout}");
    let img = viewer::read_png(&shot).unwrap();
    assert!(img.width >= 500 && img.height >= 350, "{}x{}", img.width, img.height);
    // After the rebuild the terrain is coloured by group: the 3-D view holds many distinct colours.
    let mut colours: Vec<&[u8]> = img.pixels.chunks_exact(4).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 50, "{} colours", colours.len());
}

/// A rebuild keeps what the hierarchy shown is: a quadtree without regions is rebuilt without them (not with the
/// default crystal grouping, nor with regions), one with regions with them; `--no-regions` rebuilds either, or a
/// mesh's quadtree, without them.
#[test]
fn view_rebuilds_a_quadtree_as_it_was_built() {
    let dir = tempfile::tempdir().unwrap();
    let obj = bundled("jacksboro-2k.obj");
    let build = |name: &str, extra: &[&str]| {
        let tch = dir.path().join(name);
        let out = Command::new(env!("CARGO_BIN_EXE_tincull"))
            .arg("build")
            .arg(&obj)
            .args(["--grouping", "quadtree", "--depth", "3", "-q", "-o"])
            .arg(&tch)
            .args(extra)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        tch
    };
    let bare = build("bare.tch", &["--no-regions"]);
    let full = build("full.tch", &[]);
    let shot = dir.path().join("shot.png");
    let cases: [(&std::path::Path, &[&str], bool); 4] = [
        (&bare, &["--rebuild"], false),
        (&full, &["--rebuild"], true),
        (&full, &["--rebuild", "--no-regions"], false),
        (
            &obj,
            &["--rebuild", "--grouping", "quadtree", "--depth", "3", "--no-regions"],
            false,
        ),
    ];
    for (input, args, regions) in cases {
        let Some(stdout) = view(input, args, &shot) else {
            return;
        };
        // Depth 3: 64 cells, all holding triangles on this terrain.
        assert!(
            stdout.contains("built the hierarchy 1 time; the last has 64 groups"),
            "{stdout}"
        );
        assert_eq!(
            stdout.contains("without regions"),
            !regions,
            "{}: {stdout}",
            input.display()
        );
    }
}
