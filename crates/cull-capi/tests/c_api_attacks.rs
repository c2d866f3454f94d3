//! Attacks on the C API (`tc_*`) and on `.tch` loading through it: null pointers, cameras, the buffer protocol,
//! parameters, damaged, foreign and hostile files, threads, and the C API's ranges against the Rust API's. The two
//! `regression_*` tests are defects they found, each named for what now holds.

#![allow(clippy::missing_safety_doc)]

use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use cull::{AnyCuller, BuildInfo, Camera, CullMethod, Grouping, Hierarchy, Mesh, Node, SafeParams, StoredRegion};
use tincull_cull::*;

// ---------------------------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------------------------

fn crate_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn workspace() -> PathBuf {
    crate_dir().join("../..")
}

fn last_error() -> String {
    // SAFETY: the library returns a NUL-terminated string valid until the next failing call on this thread.
    unsafe { CStr::from_ptr(tc_last_error()) }
        .to_string_lossy()
        .into_owned()
}

const METHODS: [u32; 4] = [
    TC_METHOD_SAFE,
    TC_METHOD_THESIS,
    TC_METHOD_STEWART,
    TC_METHOD_LLOYD_EGBERT,
];

fn cull_method(m: u32) -> CullMethod {
    match m {
        TC_METHOD_SAFE => CullMethod::Safe,
        TC_METHOD_THESIS => CullMethod::Thesis,
        TC_METHOD_STEWART => CullMethod::Stewart,
        _ => CullMethod::LloydEgbert,
    }
}

/// The bundled 2k mesh built with default parameters (crystal), and once more as a quadtree.
fn bundled(quadtree: bool) -> &'static Hierarchy {
    static CRYSTAL: OnceLock<Hierarchy> = OnceLock::new();
    static QUAD: OnceLock<Hierarchy> = OnceLock::new();
    let cell = if quadtree { &QUAD } else { &CRYSTAL };
    cell.get_or_init(|| {
        let obj = workspace().join("meshes/jacksboro-2k.obj");
        let (t, _) = tin::read_obj(&obj, &tin::ObjImportOptions::default()).expect("the bundled mesh");
        let mut p = pipeline::BuildParams::default();
        if quadtree {
            p.grouping = pipeline::Grouping::Quadtree(Default::default());
        }
        pipeline::build(&t, &p, None).expect("build").hierarchy
    })
}

/// A small hand-made hierarchy: an `n` x `n` grid of cells (two triangles each) 10 m apart with hills, one leaf per
/// row of cells, one root above them; `regions`: every node gets a region in every other sector.
fn grid_hierarchy(n: u32, sectors: u32, regions: bool, grouping: Grouping) -> Hierarchy {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (f64::from(i) * 10.0, f64::from(j) * 10.0);
            positions.push([
                x + 1000.0,
                y + 2000.0,
                50.0 + 20.0 * (x / 37.0).sin() * (y / 23.0).cos(),
            ]);
        }
    }
    let v = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::new();
    let mut nodes = Vec::new();
    for j in 0..n {
        let start = triangles.len() as u32;
        for i in 0..n {
            triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
        nodes.push(node_over(
            &positions,
            &triangles,
            [start, triangles.len() as u32],
            vec![],
            0,
        ));
    }
    let nt = triangles.len() as u32;
    let kids: Vec<u32> = (0..n).collect();
    nodes.push(node_over(&positions, &triangles, [0, nt], kids, 1));
    let origin = [1000.0, 2000.0, 0.0];
    for node in &mut nodes {
        node.centre = [node.centre[0] - 1000.0, node.centre[1] - 2000.0];
        if regions {
            node.regions = (0..sectors)
                .step_by(2)
                .map(|s| StoredRegion {
                    sector: s as u16,
                    points: vec![[30.0, 60.0], [200.0, 80.0], [400.0, 120.0]],
                    tail_slope: 0.1,
                })
                .collect();
        }
    }
    let h = Hierarchy {
        sectors,
        origin,
        nodes,
        roots: vec![n],
        always_visible: [nt, nt],
        mesh: Mesh { positions, triangles },
        build: BuildInfo {
            grouping,
            ..BuildInfo::default()
        },
    };
    h.check_invariants().expect("the hand-made hierarchy is valid");
    h
}

/// A node over `range` with a bounding circle (world x,y; the caller shifts it to the origin).
fn node_over(pos: &[[f64; 3]], tris: &[[u32; 3]], range: [u32; 2], children: Vec<u32>, level: u32) -> Node {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for t in &tris[range[0] as usize..range[1] as usize] {
        for &k in t {
            let p = pos[k as usize];
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
    }
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let r = ((hi[0] - lo[0]).hypot(hi[1] - lo[1]) / 2.0 + 1.0) as f32;
    Node {
        centre: [c[0] as f32, c[1] as f32],
        radius: if r.is_finite() { r } else { 0.0 },
        children,
        triangles: range,
        level,
        regions: vec![],
    }
}

/// An owned culler, freed on drop.
struct C(*mut TcCuller);

impl Drop for C {
    fn drop(&mut self) {
        // SAFETY: from tc_load_*, freed once.
        unsafe { tc_free(self.0) };
    }
}

fn load_bytes(bytes: &[u8], method: u32) -> Result<C, (i32, String)> {
    let mut c: *mut TcCuller = std::ptr::dangling_mut::<TcCuller>(); // garbage: must become NULL on failure
    // SAFETY: valid buffer and out pointer.
    let rc = unsafe { tc_load_buffer(bytes.as_ptr(), bytes.len(), method, &mut c) };
    if rc == TC_OK {
        assert!(!c.is_null());
        Ok(C(c))
    } else {
        assert!(c.is_null(), "*out must be NULL after a failed load (rc {rc})");
        Err((rc, last_error()))
    }
}

fn load_path(path: &Path, method: u32) -> Result<C, (i32, String)> {
    use std::os::unix::ffi::OsStrExt;
    let p = CString::new(path.as_os_str().as_bytes()).expect("no NUL");
    let mut c: *mut TcCuller = std::ptr::dangling_mut::<TcCuller>();
    // SAFETY: valid string and out pointer.
    let rc = unsafe { tc_load_path(p.as_ptr(), method, &mut c) };
    if rc == TC_OK {
        assert!(!c.is_null());
        Ok(C(c))
    } else {
        assert!(c.is_null(), "*out must be NULL after a failed load (rc {rc})");
        Err((rc, last_error()))
    }
}

fn info(c: &C) -> TcInfo {
    let mut i = TcInfo::default();
    // SAFETY: valid culler and out.
    assert_eq!(unsafe { tc_info(c.0, &mut i) }, TC_OK);
    i
}

/// Culls through the C API with the two-call protocol (NULL buffer for the size, then a buffer of exactly that size
/// surrounded by canaries that must stay untouched); also checks the ranges against `TcInfo::max_ranges`.
fn c_cull(c: &C, eye: [f64; 3], yaw: f64, fov: f64) -> Result<Vec<[u32; 2]>, i32> {
    let mut n = usize::MAX;
    // SAFETY: valid pointers; NULL buffer with capacity 0 is allowed.
    let rc = unsafe { tc_cull(c.0, eye.as_ptr(), yaw, fov, std::ptr::null_mut(), 0, &mut n) };
    assert_ne!(
        rc,
        TC_ERR_PANIC,
        "tc_cull panicked: {} (eye {eye:?} yaw {yaw} fov {fov})",
        last_error()
    );
    if rc != TC_OK && rc != TC_ERR_BUFFER_TOO_SMALL {
        return Err(rc);
    }
    let need = n;
    assert!(
        need <= info(c).max_ranges as usize,
        "{need} ranges exceed TcInfo::max_ranges {} (eye {eye:?} yaw {yaw} fov {fov})",
        info(c).max_ranges
    );
    const GUARD: usize = 8;
    let canary = TcRange {
        start: 0xDEAD_BEEF,
        end: 0xFEED_FACE,
    };
    let mut buf = vec![canary; need + 2 * GUARD];
    let mut got = usize::MAX;
    // Too small by one: nothing may be written.
    if need > 0 {
        // SAFETY: the buffer holds `need - 1` elements from GUARD on.
        let rc = unsafe {
            tc_cull(
                c.0,
                eye.as_ptr(),
                yaw,
                fov,
                buf.as_mut_ptr().add(GUARD),
                need - 1,
                &mut got,
            )
        };
        assert_eq!(rc, TC_ERR_BUFFER_TOO_SMALL);
        assert_eq!(got, need, "*count on BUFFER_TOO_SMALL");
        assert!(
            buf.iter().all(|r| *r == canary),
            "tc_cull wrote into a too-small buffer"
        );
    }
    // SAFETY: the buffer holds `need` elements from GUARD on.
    let rc = unsafe { tc_cull(c.0, eye.as_ptr(), yaw, fov, buf.as_mut_ptr().add(GUARD), need, &mut got) };
    assert_eq!(rc, TC_OK, "{}", last_error());
    assert_eq!(got, need, "same camera, same count");
    assert!(
        buf[..GUARD].iter().chain(&buf[GUARD + need..]).all(|r| *r == canary),
        "canary overwritten"
    );
    let ranges: Vec<[u32; 2]> = buf[GUARD..GUARD + need].iter().map(|r| [r.start, r.end]).collect();
    // Ascending, merged, non-empty, within the triangles.
    let nt = info(c).triangles;
    for w in ranges.windows(2) {
        assert!(w[0][1] < w[1][0], "ranges not ascending and merged: {w:?}");
    }
    for r in &ranges {
        assert!(r[0] < r[1] && r[1] <= nt, "bad range {r:?} of {nt} triangles");
    }
    let mut st = TcStats::default();
    // SAFETY: valid pointers.
    assert_eq!(unsafe { tc_stats(c.0, &mut st) }, TC_OK);
    let drawn: u32 = ranges.iter().map(|r| r[1] - r[0]).sum();
    assert_eq!(st.ranges as usize, need, "TcStats::ranges");
    assert_eq!(st.triangles_drawn, drawn, "TcStats::triangles_drawn");
    assert_eq!(
        st.triangles_drawn + st.triangles_culled,
        nt,
        "drawn + culled = triangles"
    );
    Ok(ranges)
}

/// The Rust API's ranges for the same view and parameters.
fn rust_cull(h: &Hierarchy, m: u32, params: SafeParams, eye: [f64; 3], yaw: f64, fov: f64) -> Vec<[u32; 2]> {
    let camera = Camera::from_degrees(eye, yaw, fov).expect("a valid camera");
    AnyCuller::with_params(h, cull_method(m), params).cull(&camera).ranges
}

/// Cameras around a hierarchy: over the vertices, high above, far away, below, and odd but finite values.
fn cameras(h: &Hierarchy) -> Vec<([f64; 3], f64, f64)> {
    let p = &h.mesh.positions;
    let mut out = Vec::new();
    let step = (p.len() / 10).max(1);
    for (i, v) in p.iter().step_by(step).enumerate() {
        let fov = [360.0, 90.0, 30.0, 179.9, 359.99, 1e-9][i % 6];
        out.push(([v[0], v[1], v[2] + 2.0], 37.0 * i as f64, fov));
    }
    let o = h.origin;
    for (eye, yaw, fov) in [
        ([o[0], o[1], o[2] + 1e4], 0.0, 360.0),
        ([o[0] - 1e5, o[1] + 3e5, o[2] + 10.0], 1e300, 60.0),
        ([o[0], o[1], o[2] - 1e4], -720.5, 90.0),
        ([0.0, 0.0, 0.0], 0.0, 5e-324),
        ([1e300, -1e300, 1e300], 0.0, 360.0),
        ([f64::MAX, f64::MAX, f64::MAX], 45.0, 90.0),
        ([-f64::MAX, f64::MAX, -f64::MAX], -1e-300, 360.0),
        ([f64::MIN_POSITIVE, -5e-324, 0.0], 180.0, 1.0),
        ([o[0] + 1e-300, o[1], o[2] + 1e30], 90.0, 90.0),
    ] {
        out.push((eye, yaw, fov));
    }
    out
}

/// Loads `h` through the C API with every method it takes, and checks every camera: no panic, the buffer protocol,
/// and the Rust API's ranges.
fn check_all_methods(h: &Hierarchy, label: &str) {
    let bytes = h.to_bytes().expect("to_bytes");
    for m in METHODS {
        let c = match load_bytes(&bytes, m) {
            Ok(c) => c,
            Err((rc, e)) => {
                assert_ne!(rc, TC_ERR_PANIC, "{label}: load panicked: {e}");
                assert!(
                    cull_method(m).check(h).is_err(),
                    "{label}: method {m} refused: {rc} {e}"
                );
                continue;
            }
        };
        for (eye, yaw, fov) in cameras(h) {
            let got = c_cull(&c, eye, yaw, fov).unwrap_or_else(|rc| panic!("{label}: rc {rc}: {}", last_error()));
            let want = rust_cull(h, m, SafeParams::default(), eye, yaw, fov);
            assert_eq!(
                got, want,
                "{label}: method {m}, eye {eye:?} yaw {yaw} fov {fov}: C and Rust differ"
            );
        }
    }
}

/// Frames `payload` as a `.tch` with `version` (correct length and checksum).
fn tch(version: u32, payload: &[u8]) -> Vec<u8> {
    cull::file::frame(&cull::MAGIC, version, payload)
}

/// The payload of a `.tch`.
fn payload_of(bytes: &[u8]) -> Vec<u8> {
    bytes[cull::file::HEADER_LEN..].to_vec()
}

// ---------------------------------------------------------------------------------------------------------------
// Regressions
// ---------------------------------------------------------------------------------------------------------------

/// Regression: `tc_load_path` on a pipe (a named pipe, `/dev/stdin`, `/dev/fd/N`) kept its bytes in a process-wide
/// table keyed by the path, forever: a renderer that loaded through a pipe path a second time (fd numbers are reused)
/// got the first pipe's hierarchy back, even once a regular file stood at that path. Only the command line keeps
/// pipes now (`infile::keep_pipes`).
#[test]
fn regression_every_load_of_a_pipe_path_reads_what_it_names_then() {
    use std::io::Write;
    let small = grid_hierarchy(2, 8, false, Grouping::Crystal)
        .to_bytes()
        .expect("to_bytes");
    let big = grid_hierarchy(6, 8, false, Grouping::Crystal)
        .to_bytes()
        .expect("to_bytes");
    let dir = tempfile::tempdir().expect("tempdir");
    let fifo = dir.path().join("terrain.tch");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    // One writer per load: the same named pipe fed twice, first a 2x2 grid (8 triangles), then a 6x6 one (72).
    let load_through_pipe = |bytes: Vec<u8>| {
        let path = fifo.clone();
        let w = std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(&path)
                .expect("open the FIFO to write");
            let _ = f.write_all(&bytes);
        });
        let r = load_path(&fifo, TC_METHOD_SAFE).map(|c| info(&c).triangles);
        w.join().expect("writer");
        r
    };
    let first = load_through_pipe(small);
    assert_eq!(first, Ok(8), "the first pipe holds the 2x2 grid");
    // A second writer with a bigger grid. Were the first pipe's bytes kept, the load would not open the pipe, and
    // the writer would wait for a reader: then read its end here, so that the test fails instead of hanging.
    let path = fifo.clone();
    let w = std::thread::spawn(move || {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .expect("open the FIFO to write");
        let _ = f.write_all(&big);
    });
    let second = load_path(&fifo, TC_METHOD_SAFE).map(|c| info(&c).triangles);
    if second != Ok(72) {
        let _ = std::fs::File::open(&fifo).map(|mut f| std::io::Read::read_to_end(&mut f, &mut Vec::new()));
    }
    w.join().expect("writer");
    // Once the path holds a regular file (the pipe removed, the file written in its place), that file is read.
    std::fs::remove_file(&fifo).expect("remove the FIFO");
    std::fs::write(
        &fifo,
        grid_hierarchy(6, 8, false, Grouping::Crystal)
            .to_bytes()
            .expect("to_bytes"),
    )
    .expect("write");
    let third = load_path(&fifo, TC_METHOD_SAFE).map(|c| info(&c).triangles);
    eprintln!("first {first:?}, second {second:?}, regular file at the same path {third:?}");
    assert_eq!(
        second,
        Ok(72),
        "the second load of the named pipe {} (a new writer sending a 6x6 grid of 72 triangles) returned the FIRST \
         hierarchy again without reading the pipe: infile keeps every pipe's bytes by path for the life of the process",
        fifo.display()
    );
    assert_eq!(third, Ok(72), "the regular file at the pipe's path");
}

/// Regression: `postcard::from_bytes` ignored unread payload bytes, so junk appended inside the framed payload (with
/// a matching checksum) loaded, and a version-2 quadtree payload framed as version 1 (every version-1 file is
/// crystal-grouped) loaded as a quadtree, the crystal byte appended for version 1 left over.
#[test]
fn regression_bytes_left_inside_the_payload_are_refused() {
    let h = grid_hierarchy(3, 8, false, Grouping::Crystal);
    let mut payload = payload_of(&h.to_bytes().expect("to_bytes"));
    payload.extend_from_slice(b"garbage after the hierarchy, with a matching checksum");
    let r = load_bytes(&tch(cull::FORMAT_VERSION, &payload), TC_METHOD_SAFE).map(|_| ());
    let quad = grid_hierarchy(
        3,
        8,
        false,
        Grouping::Quadtree {
            built_depth: 2,
            stored_depth: 2,
        },
    );
    let as_v1 = tch(1, &payload_of(&quad.to_bytes().expect("to_bytes")));
    let stewart_on_v1 = load_bytes(&as_v1, TC_METHOD_STEWART).map(|_| ());
    assert!(
        matches!(r, Err((TC_ERR_FORMAT, _))) && stewart_on_v1.is_err(),
        "junk inside the payload loaded: {r:?}; a version-1 file loaded as a quadtree (stewart accepted): \
         {stewart_on_v1:?}"
    );
}

// ---------------------------------------------------------------------------------------------------------------
// Attacks withstood (kept)
// ---------------------------------------------------------------------------------------------------------------

/// Every NULL that the docs say gives `TC_ERR_NULL` does, with a message; `*out` is NULL after every failed load.
#[test]
fn attack_null_pointers_everywhere() {
    let bytes = grid_hierarchy(3, 8, false, Grouping::Crystal)
        .to_bytes()
        .expect("to_bytes");
    let c = load_bytes(&bytes, TC_METHOD_SAFE).expect("load");
    let eye = [1010.0, 2010.0, 200.0];
    let mut n = 0usize;
    let mut r = [TcRange::default(); 4];
    let mut params = TcParams::default();
    // SAFETY: NULLs are the library's own checks; everything else is valid.
    unsafe {
        let mut out: *mut TcCuller = std::ptr::dangling_mut::<TcCuller>();
        assert_eq!(
            tc_load_buffer(std::ptr::null(), 10, TC_METHOD_SAFE, &mut out),
            TC_ERR_NULL
        );
        assert!(out.is_null());
        out = std::ptr::dangling_mut::<TcCuller>();
        assert_eq!(
            tc_load_buffer(std::ptr::null(), 0, TC_METHOD_SAFE, &mut out),
            TC_ERR_NULL
        );
        assert!(out.is_null());
        assert_eq!(
            tc_load_buffer(bytes.as_ptr(), bytes.len(), 0, std::ptr::null_mut()),
            TC_ERR_NULL
        );
        assert_eq!(tc_load_path(c"x".as_ptr(), 0, std::ptr::null_mut()), TC_ERR_NULL);
        assert_eq!(
            tc_cull(std::ptr::null_mut(), eye.as_ptr(), 0.0, 90.0, r.as_mut_ptr(), 4, &mut n),
            TC_ERR_NULL
        );
        assert_eq!(
            tc_cull(c.0, std::ptr::null(), 0.0, 90.0, r.as_mut_ptr(), 4, &mut n),
            TC_ERR_NULL
        );
        assert_eq!(
            tc_cull(c.0, eye.as_ptr(), 0.0, 90.0, r.as_mut_ptr(), 4, std::ptr::null_mut()),
            TC_ERR_NULL
        );
        assert_eq!(
            tc_cull(c.0, eye.as_ptr(), 0.0, 90.0, std::ptr::null_mut(), 4, &mut n),
            TC_ERR_NULL
        );
        assert_eq!(tc_info(c.0, std::ptr::null_mut()), TC_ERR_NULL);
        assert_eq!(tc_info(std::ptr::null(), &mut TcInfo::default()), TC_ERR_NULL);
        assert_eq!(tc_mesh(c.0, std::ptr::null_mut()), TC_ERR_NULL);
        assert_eq!(tc_stats(c.0, std::ptr::null_mut()), TC_ERR_NULL);
        assert_eq!(tc_work(c.0, std::ptr::null_mut()), TC_ERR_NULL);
        assert_eq!(tc_get_params(c.0, std::ptr::null_mut()), TC_ERR_NULL);
        assert_eq!(tc_get_params(std::ptr::null(), &mut params), TC_ERR_NULL);
        assert_eq!(tc_set_params(c.0, std::ptr::null()), TC_ERR_NULL);
        assert_eq!(tc_set_params(std::ptr::null_mut(), &params), TC_ERR_NULL);
        assert_eq!(tc_default_params(std::ptr::null_mut()), TC_ERR_NULL);
        assert!(!last_error().is_empty());
        tc_free(std::ptr::null_mut());
    }
}

/// A fresh thread has an empty message; a successful call does not clear the last failure's message.
#[test]
fn attack_last_error_per_thread() {
    std::thread::spawn(|| {
        assert_eq!(last_error(), "");
        let mut out: *mut TcCuller = std::ptr::null_mut();
        // SAFETY: NULL path is checked.
        assert_eq!(unsafe { tc_load_path(std::ptr::null(), 0, &mut out) }, TC_ERR_NULL);
        let e = last_error();
        assert!(e.contains("path is NULL"));
        assert_eq!(tc_abi_version(), TC_ABI_VERSION);
        let mut p = TcParams::default();
        // SAFETY: valid out.
        assert_eq!(unsafe { tc_default_params(&mut p) }, TC_OK);
        assert_eq!(last_error(), e);
        std::thread::spawn(|| assert_eq!(last_error(), ""))
            .join()
            .expect("inner");
    })
    .join()
    .expect("thread");
}

/// Non-finite and out-of-range cameras are TC_ERR_INVALID (never a panic), leave `*count` and the counters alone;
/// odd finite ones cull, as the Rust API does.
#[test]
fn attack_camera_values() {
    let h = grid_hierarchy(6, 8, true, Grouping::Crystal);
    let bytes = h.to_bytes().expect("to_bytes");
    let c = load_bytes(&bytes, TC_METHOD_SAFE).expect("load");
    let good = [1030.0, 2030.0, 300.0];
    c_cull(&c, good, 0.0, 90.0).expect("culls");
    let mut before = TcStats::default();
    // SAFETY: valid culler and out.
    unsafe { tc_stats(c.0, &mut before) };
    let bad: Vec<([f64; 3], f64, f64)> = vec![
        ([f64::NAN, 0.0, 0.0], 0.0, 90.0),
        ([0.0, f64::INFINITY, 0.0], 0.0, 90.0),
        ([0.0, 0.0, f64::NEG_INFINITY], 0.0, 90.0),
        (good, f64::NAN, 90.0),
        (good, f64::NEG_INFINITY, 90.0),
        (good, 0.0, f64::NAN),
        (good, 0.0, 0.0),
        (good, 0.0, -0.0),
        (good, 0.0, -1.0),
        (good, 0.0, 360.000_000_000_1),
        (good, 0.0, f64::INFINITY),
    ];
    for (eye, yaw, fov) in bad {
        let mut n = 12345usize;
        // SAFETY: valid pointers.
        let rc = unsafe { tc_cull(c.0, eye.as_ptr(), yaw, fov, std::ptr::null_mut(), 0, &mut n) };
        assert_eq!(rc, TC_ERR_INVALID, "eye {eye:?} yaw {yaw} fov {fov}");
        assert!(last_error().starts_with("tc_cull: "), "{}", last_error());
        assert_eq!(n, 12345, "*count left alone on INVALID");
        let mut after = TcStats::default();
        // SAFETY: valid culler and out.
        unsafe { tc_stats(c.0, &mut after) };
        assert_eq!(after, before, "counters of a refused cull");
    }
}

/// C and Rust give the same ranges on the bundled hierarchies for every method and a spread of cameras (including
/// extreme finite ones), through the two-call buffer protocol with canaries.
#[test]
fn attack_c_equals_rust_on_bundled_hierarchies() {
    check_all_methods(bundled(false), "jacksboro crystal");
    check_all_methods(bundled(true), "jacksboro quadtree");
}

/// After `tc_set_params`, the C culler equals the Rust culler given the same parameters; refusals leave it
/// unchanged; `work <= work_budget` as `TcWork` documents.
#[test]
fn attack_params_edges() {
    let h = bundled(false);
    let bytes = h.to_bytes().expect("to_bytes");
    let c = load_bytes(&bytes, TC_METHOD_SAFE).expect("load");
    let mut d = TcParams::default();
    // SAFETY: valid pointers throughout.
    unsafe {
        assert_eq!(tc_default_params(&mut d), TC_OK);
        let mut w = TcWork {
            work: 9,
            occluder_edges: 9,
        };
        assert_eq!(tc_work(c.0, &mut w), TC_OK);
        assert_eq!(w, TcWork::default(), "zeros before the first cull");
        let refused = [
            TcParams {
                columns_per_face: 0,
                ..d
            },
            TcParams {
                columns_per_face: 1,
                ..d
            },
            TcParams {
                columns_per_face: 3,
                ..d
            },
            TcParams {
                columns_per_face: 131072,
                ..d
            },
            TcParams {
                columns_per_face: u32::MAX,
                ..d
            },
            TcParams {
                columns_per_face: 1 << 31,
                ..d
            },
            TcParams { patch: 0, ..d },
            TcParams { patch: 65, ..d },
            TcParams { patch: u32::MAX, ..d },
        ];
        for p in refused {
            assert_eq!(tc_set_params(c.0, &p), TC_ERR_INVALID, "{p:?}");
            let mut now = TcParams::default();
            assert_eq!(tc_get_params(c.0, &mut now), TC_OK);
            assert_eq!(now, d, "refused params change nothing");
        }
        let eyes = cameras(h);
        let accepted = [
            TcParams { work_budget: 0, ..d },
            TcParams { work_budget: 1, ..d },
            TcParams { work_budget: 7, ..d },
            TcParams {
                work_budget: 300,
                columns_per_face: 2,
                ..d
            },
            TcParams {
                occluder_budget: 0,
                ..d
            },
            TcParams {
                occluder_budget: 1,
                work_budget: u32::MAX,
                ..d
            },
            TcParams {
                coarse_columns: u32::MAX,
                ..d
            },
            TcParams {
                coarse_columns: 3,
                work_budget: 50,
                patch: 1,
                ..d
            },
            TcParams {
                columns_per_face: 65536,
                patch: 64,
                ..d
            },
        ];
        for p in accepted {
            let (mut s0, mut w0) = (TcStats::default(), TcWork::default());
            tc_stats(c.0, &mut s0);
            tc_work(c.0, &mut w0);
            assert_eq!(tc_set_params(c.0, &p), TC_OK, "{p:?}: {}", last_error());
            let (mut s1, mut w1) = (TcStats::default(), TcWork::default());
            tc_stats(c.0, &mut s1);
            tc_work(c.0, &mut w1);
            assert_eq!(
                (s0, w0),
                (s1, w1),
                "the counters of the last cull stay across tc_set_params"
            );
            let mut now = TcParams::default();
            assert_eq!(tc_get_params(c.0, &mut now), TC_OK);
            assert_eq!(now, p, "get_params returns what was set");
            let sp = SafeParams {
                columns_per_face: p.columns_per_face as usize,
                patch: p.patch as usize,
                occluder_budget: if p.occluder_budget == u32::MAX {
                    usize::MAX
                } else {
                    p.occluder_budget as usize
                },
                work_budget: if p.work_budget == u32::MAX {
                    usize::MAX
                } else {
                    p.work_budget as usize
                },
                coarse_columns: p.coarse_columns as usize,
            };
            for &(eye, yaw, fov) in eyes.iter().step_by(3) {
                let got = c_cull(&c, eye, yaw, fov).expect("culls");
                assert_eq!(
                    got,
                    rust_cull(h, TC_METHOD_SAFE, sp, eye, yaw, fov),
                    "{p:?} eye {eye:?}"
                );
                let mut w = TcWork::default();
                assert_eq!(tc_work(c.0, &mut w), TC_OK);
                assert!(
                    w.work <= p.work_budget,
                    "work {} over the budget {} ({p:?})",
                    w.work,
                    p.work_budget
                );
            }
        }
        // Region cullers have none; lloyd-egbert takes columns only.
        let t = load_bytes(&bytes, TC_METHOD_THESIS).expect("load");
        assert_eq!(tc_set_params(t.0, &d), TC_ERR_INVALID);
        assert_eq!(tc_get_params(t.0, &mut TcParams::default()), TC_ERR_INVALID);
        let le = load_bytes(&bytes, TC_METHOD_LLOYD_EGBERT).expect("load");
        assert_eq!(tc_set_params(le.0, &TcParams { patch: 8, ..d }), TC_ERR_INVALID);
        assert_eq!(
            tc_set_params(
                le.0,
                &TcParams {
                    work_budget: u32::MAX,
                    ..d
                }
            ),
            TC_ERR_INVALID
        );
        assert_eq!(
            tc_set_params(
                le.0,
                &TcParams {
                    columns_per_face: 4,
                    ..d
                }
            ),
            TC_OK
        );
        for &(eye, yaw, fov) in eyes.iter().step_by(2) {
            let sp = SafeParams {
                columns_per_face: 4,
                ..SafeParams::default()
            };
            assert_eq!(
                c_cull(&le, eye, yaw, fov).expect("culls"),
                rust_cull(h, 3, sp, eye, yaw, fov)
            );
            let mut w = TcWork {
                work: 1,
                occluder_edges: 1,
            };
            assert_eq!(tc_work(le.0, &mut w), TC_OK);
            assert_eq!(w, TcWork::default(), "zeros for lloyd-egbert");
        }
    }
}

/// Every truncation and many bit flips of a real `.tch` give FORMAT (or, for a flip that keeps it valid, OK): never
/// a panic, and the buffer is only read within `len` (the copy the test passes is exactly that long).
#[test]
fn attack_truncations_and_flips() {
    let bytes = grid_hierarchy(4, 8, true, Grouping::Crystal)
        .to_bytes()
        .expect("to_bytes");
    for len in 0..bytes.len() {
        let cut = bytes[..len].to_vec();
        match load_bytes(&cut, TC_METHOD_SAFE) {
            Err((TC_ERR_FORMAT, e)) => assert!(e.starts_with("tc_load_buffer: memory buffer: "), "{e}"),
            other => panic!("truncated to {len}: {:?}", other.map(|_| ())),
        }
    }
    // Flips in the header are caught by magic, version, length or checksum; flips in the payload by the checksum.
    for at in 0..bytes.len() {
        for bit in [0u8, 3, 7] {
            let mut b = bytes.clone();
            b[at] ^= 1 << bit;
            match load_bytes(&b, TC_METHOD_SAFE) {
                Err((TC_ERR_FORMAT, _)) => {}
                Ok(_) if (8..12).contains(&at) => {} // version 2 -> 3 fails, 2 -> ... only 1 or 2 pass
                other => panic!("flip at {at} bit {bit}: {:?}", other.map(|_| ())),
            }
        }
    }
    // Payload flips with a recomputed checksum: the decoder and the structural checks must catch them (or accept a
    // still-valid hierarchy, which must then cull without panicking).
    let payload = payload_of(&bytes);
    let mut accepted = 0;
    for at in 0..payload.len() {
        for bit in [0u8, 1, 6, 7] {
            let mut p = payload.clone();
            p[at] ^= 1 << bit;
            for m in [TC_METHOD_SAFE, TC_METHOD_THESIS, TC_METHOD_LLOYD_EGBERT] {
                match load_bytes(&tch(2, &p), m) {
                    Err((rc, e)) => assert!(rc == TC_ERR_FORMAT || rc == TC_ERR_INVALID, "{rc}: {e}"),
                    Ok(c) => {
                        accepted += 1;
                        let h = Hierarchy::from_bytes(&tch(2, &p)).expect("loads in Rust too");
                        for (eye, yaw, fov) in cameras(&h).into_iter().step_by(4) {
                            let got = c_cull(&c, eye, yaw, fov).expect("culls");
                            assert_eq!(got, rust_cull(&h, m, SafeParams::default(), eye, yaw, fov));
                        }
                    }
                }
            }
        }
    }
    eprintln!("payload flips accepted as valid hierarchies: {accepted}");
}

/// Header attacks: magic, version (0, 3, MAX), length field (0, one more, u64::MAX), trailing bytes, checksum, a PVS
/// file's frame, text files (OBJ), all `TC_ERR_FORMAT` with a clear message.
#[test]
fn attack_header_and_foreign_files() {
    let bytes = grid_hierarchy(2, 8, false, Grouping::Crystal)
        .to_bytes()
        .expect("to_bytes");
    let payload = payload_of(&bytes);
    let mut cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("version 0", tch(0, &payload), "unsupported hierarchy format version 0"),
        ("version 3", tch(3, &payload), "unsupported hierarchy format version 3"),
        ("version max", tch(u32::MAX, &payload), "unsupported"),
        (
            "pvs frame",
            cull::file::frame(b"TINCPVS\x1a", 1, &payload),
            "wrong magic",
        ),
        ("obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(), "wrong magic"),
        ("magic only", cull::MAGIC.to_vec(), "truncated"),
        ("trailing", [bytes.clone(), vec![0]].concat(), "1 unexpected bytes"),
    ];
    for (what, len) in [
        ("len 0", 0u64),
        ("len +1", payload.len() as u64 + 1),
        ("len max", u64::MAX),
    ] {
        let mut b = bytes.clone();
        b[12..20].copy_from_slice(&len.to_le_bytes());
        cases.push((
            what,
            b,
            if len == 0 {
                "unexpected bytes"
            } else {
                "truncated or corrupt"
            },
        ));
    }
    let mut b = bytes.clone();
    b[20] ^= 0xff;
    cases.push(("crc", b, "checksum"));
    for (what, b, expect) in cases {
        match load_bytes(&b, TC_METHOD_SAFE) {
            Err((TC_ERR_FORMAT, e)) => assert!(e.contains(expect), "{what}: {e}"),
            other => panic!("{what}: {:?}", other.map(|_| ())),
        }
    }
    // Through the path too: a directory, character devices, an empty file, an OBJ, a missing file.
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = dir.path().join("mesh.tch");
    std::fs::write(&obj, b"v 0 0 0\n").expect("write");
    let empty = dir.path().join("empty.tch");
    std::fs::write(&empty, b"").expect("write");
    for (p, want) in [
        (dir.path().to_path_buf(), TC_ERR_IO),
        (PathBuf::from("/dev/zero"), TC_ERR_IO),
        (PathBuf::from("/dev/null"), TC_ERR_IO),
        (PathBuf::from(""), TC_ERR_IO),
        (PathBuf::from("x".repeat(10_000)), TC_ERR_IO),
        (obj, TC_ERR_FORMAT),
        (empty, TC_ERR_FORMAT),
    ] {
        match load_path(&p, TC_METHOD_SAFE) {
            Err((rc, e)) => assert_eq!(rc, want, "{}: {e}", p.display()),
            Ok(_) => panic!("{} loaded", p.display()),
        }
    }
    // An empty path is said to be one (not "tc_load_path: : No such file or directory").
    let (_, e) = load_path(Path::new(""), TC_METHOD_SAFE).err().expect("refused");
    assert_eq!(e, "tc_load_path: the path is empty");
}

/// Hostile postcard counts (a node, vertex or root count of 2^60, with a matching checksum) are refused at once,
/// without allocating for them.
#[test]
fn attack_huge_counts() {
    fn varint(mut v: u64, out: &mut Vec<u8>) {
        loop {
            let b = (v & 0x7f) as u8;
            v >>= 7;
            if v == 0 {
                out.push(b);
                return;
            }
            out.push(b | 0x80);
        }
    }
    let mut cases = Vec::new();
    // sectors, origin, nodes count huge.
    let mut p = Vec::new();
    varint(8, &mut p);
    p.extend_from_slice(&[0u8; 24]);
    varint(1 << 60, &mut p);
    cases.push(p.clone());
    // 0 nodes, roots count huge.
    let mut p = Vec::new();
    varint(8, &mut p);
    p.extend_from_slice(&[0u8; 24]);
    varint(0, &mut p);
    varint(u64::MAX, &mut p);
    cases.push(p);
    // 0 nodes, 0 roots, always visible, positions count huge followed by some data.
    let mut p = Vec::new();
    varint(8, &mut p);
    p.extend_from_slice(&[0u8; 24]);
    varint(0, &mut p);
    varint(0, &mut p);
    varint(0, &mut p);
    varint(0, &mut p);
    varint(1 << 58, &mut p);
    p.extend_from_slice(&vec![0u8; 1 << 16]);
    cases.push(p);
    for p in cases {
        let t = Instant::now();
        match load_bytes(&tch(2, &p), TC_METHOD_SAFE) {
            Err((TC_ERR_FORMAT, e)) => assert!(e.contains("cannot decode"), "{e}"),
            other => panic!("{:?}", other.map(|_| ())),
        }
        assert!(t.elapsed() < Duration::from_secs(2), "{:?}", t.elapsed());
    }
}

/// Structurally invalid hierarchies (encoded with valid framing) are `TC_ERR_FORMAT` naming the element.
#[test]
fn attack_structural_damage() {
    let base = grid_hierarchy(3, 8, true, Grouping::Crystal);
    let root = base.nodes.len() - 1;
    type Edit = Box<dyn Fn(&mut Hierarchy)>;
    let edits: Vec<(&str, Edit)> = vec![
        ("node range beyond", Box::new(|h| h.nodes[0].triangles = [0, 1_000_000])),
        ("node range reversed", Box::new(|h| h.nodes[0].triangles = [5, 2])),
        ("child beyond", Box::new(move |h| h.nodes[root].children.push(99))),
        (
            "child self",
            Box::new(move |h| h.nodes[root].children.push(root as u32)),
        ),
        (
            "child cycle",
            Box::new(move |h| {
                h.nodes[0].children = vec![root as u32];
                h.nodes[0].level = 5;
            }),
        ),
        ("two parents", Box::new(move |h| h.nodes[root].children.push(0))),
        ("root repeated", Box::new(move |h| h.roots.push(root as u32))),
        ("root beyond", Box::new(|h| h.roots.push(1000))),
        ("no roots", Box::new(|h| h.roots.clear())),
        ("nan position", Box::new(|h| h.mesh.positions[3][2] = f64::NAN)),
        ("inf position", Box::new(|h| h.mesh.positions[0][0] = f64::INFINITY)),
        ("huge position", Box::new(|h| h.mesh.positions[0][0] = 1e31)),
        ("tiny position", Box::new(|h| h.mesh.positions[0][1] = 1e-40)),
        ("nan origin", Box::new(|h| h.origin[1] = f64::NAN)),
        ("vertex beyond", Box::new(|h| h.mesh.triangles[0][2] = 10_000)),
        ("sectors 0", Box::new(|h| h.sectors = 0)),
        ("sectors 1025", Box::new(|h| h.sectors = 1025)),
        ("region sector beyond", Box::new(|h| h.nodes[0].regions[0].sector = 8)),
        ("regions out of order", Box::new(|h| h.nodes[0].regions.reverse())),
        (
            "region nan",
            Box::new(|h| h.nodes[0].regions[0].points[1][1] = f32::NAN),
        ),
        ("region empty", Box::new(|h| h.nodes[0].regions[0].points.clear())),
        (
            "region not increasing",
            Box::new(|h| h.nodes[0].regions[0].points[1][0] = 10.0),
        ),
        (
            "tail inf",
            Box::new(|h| h.nodes[0].regions[0].tail_slope = f32::INFINITY),
        ),
        ("radius nan", Box::new(|h| h.nodes[0].radius = f32::NAN)),
        ("radius negative", Box::new(|h| h.nodes[0].radius = -1.0)),
        ("centre inf", Box::new(|h| h.nodes[0].centre[0] = f32::INFINITY)),
        ("leaf level", Box::new(|h| h.nodes[0].level = 1)),
        ("always visible", Box::new(|h| h.always_visible = [0, 3])),
        (
            "gap",
            Box::new(|h| h.always_visible = [h.always_visible[0] + 1, h.always_visible[1] + 1]),
        ),
    ];
    for (what, edit) in edits {
        let mut h = base.clone();
        edit(&mut h);
        let bytes = h.to_bytes().expect("to_bytes");
        match load_bytes(&bytes, TC_METHOD_SAFE) {
            Err((TC_ERR_FORMAT, e)) => assert!(e.contains("invalid hierarchy"), "{what}: {e}"),
            other => panic!("{what}: {:?}", other.map(|_| ())),
        }
    }
}

/// Valid but hostile hierarchies: empty, always-visible only, a 100 000-deep chain, 100 000 empty leaves, degenerate
/// and extreme coordinates, extreme regions and circles, 1 and 1024 sectors, a quadtree of absurd depth. Every
/// method loads and culls them like the Rust API, within the buffer `max_ranges` gives.
#[test]
fn attack_valid_but_hostile_hierarchies() {
    let grid = grid_hierarchy(4, 8, true, Grouping::Crystal);
    let nt = grid.mesh.triangles.len() as u32;
    let mut list: Vec<(&str, Hierarchy)> = Vec::new();
    let empty = Hierarchy {
        sectors: 1,
        origin: [0.0; 3],
        nodes: vec![],
        roots: vec![],
        always_visible: [0, 0],
        mesh: Mesh::default(),
        build: BuildInfo::default(),
    };
    empty.check_invariants().expect("valid");
    list.push(("empty", empty));
    let mut orphans = grid.clone();
    orphans.nodes.clear();
    orphans.roots.clear();
    orphans.always_visible = [0, nt];
    list.push(("orphans only", orphans));
    // A chain: node k has the single child k + 1; all cover every triangle.
    let depth = 100_000u32;
    let mut chain = grid.clone();
    let leaf = chain.nodes[0].clone();
    chain.nodes = (0..depth)
        .map(|k| Node {
            children: if k + 1 < depth { vec![k + 1] } else { vec![] },
            triangles: [0, nt],
            level: depth - 1 - k,
            radius: 1e4,
            ..leaf.clone()
        })
        .collect();
    chain.roots = vec![0];
    list.push(("deep chain", chain));
    // Many empty leaves around one full one.
    let mut wide = grid.clone();
    let mut nodes: Vec<Node> = (0..100_000)
        .map(|_| Node {
            triangles: [0, 0],
            regions: vec![],
            ..leaf.clone()
        })
        .collect();
    nodes.push(Node {
        triangles: [0, nt],
        regions: vec![],
        ..leaf.clone()
    });
    let kids: Vec<u32> = (0..nodes.len() as u32).collect();
    nodes.push(Node {
        children: kids,
        triangles: [0, nt],
        level: 1,
        regions: vec![],
        ..leaf.clone()
    });
    wide.roots = vec![nodes.len() as u32 - 1];
    wide.nodes = nodes;
    list.push(("wide", wide));
    // Degenerate: every vertex at one point; collinear vertices.
    let mut point = grid.clone();
    point.mesh.positions.iter_mut().for_each(|p| *p = [1000.0, 2000.0, 0.0]);
    list.push(("one point", point));
    let mut line = grid.clone();
    line.mesh
        .positions
        .iter_mut()
        .enumerate()
        .for_each(|(i, p)| *p = [i as f64, 0.0, i as f64]);
    list.push(("collinear", line));
    // Extreme coordinates: 2^100 and 2^-100 mixed.
    let mut extreme = grid.clone();
    let big = cull::hierarchy::COORDINATE_LIMIT;
    extreme.mesh.positions.iter_mut().enumerate().for_each(|(i, p)| {
        *p = match i % 4 {
            0 => [big, -big, big],
            1 => [-big, big, 1.0 / big],
            2 => [1.0 / big, 0.0, -big],
            _ => p.map(|c| c * 1e25),
        }
    });
    extreme.origin = [-big, big, -big];
    list.push(("extreme coordinates", extreme));
    // Extreme stored values.
    let mut regions = grid.clone();
    for n in &mut regions.nodes {
        n.centre = [f32::MAX, -f32::MAX];
        n.radius = f32::MAX;
        for r in &mut n.regions {
            r.points = vec![[-f32::MAX, f32::MAX], [0.0, -f32::MAX], [f32::MAX, f32::MAX]];
            r.tail_slope = -f32::MAX;
        }
    }
    list.push(("extreme regions", regions));
    let mut tiny = grid.clone();
    for n in &mut tiny.nodes {
        n.radius = 0.0;
        for r in &mut n.regions {
            r.points = vec![[f32::MIN_POSITIVE, 1e30]];
            r.tail_slope = 0.0;
        }
    }
    list.push(("zero radius, huge regions", tiny));
    list.push(("1 sector", grid_hierarchy(4, 1, true, Grouping::Crystal)));
    list.push(("2 sectors", grid_hierarchy(4, 2, true, Grouping::Crystal)));
    list.push(("1024 sectors", grid_hierarchy(4, 1024, true, Grouping::Crystal)));
    list.push((
        "absurd quadtree",
        grid_hierarchy(
            4,
            16,
            true,
            Grouping::Quadtree {
                built_depth: u32::MAX,
                stored_depth: u32::MAX,
            },
        ),
    ));
    let mut flat = grid_hierarchy(5, 16, true, Grouping::Crystal);
    flat.mesh.positions.iter_mut().for_each(|p| p[2] = 0.0);
    list.push(("flat", flat));
    for (label, h) in &list {
        h.check_invariants().unwrap_or_else(|e| panic!("{label}: {e}"));
        let t = Instant::now();
        check_all_methods(h, label);
        eprintln!("{label}: {:?}", t.elapsed());
    }
}

/// A small xorshift generator for the random hierarchies.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        if n == 0 { 0 } else { self.next() % n }
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn pick_f32(&mut self, lo: f32, hi: f32) -> f32 {
        match self.below(20) {
            0 => f32::MAX,
            1 => -f32::MAX,
            2 => 0.0,
            3 => f32::MIN_POSITIVE,
            _ => lo + (hi - lo) * self.unit() as f32,
        }
    }
}

/// A random structurally valid hierarchy (not a height field: random triangles over random vertices).
fn random_hierarchy(g: &mut Rng) -> Hierarchy {
    let nv = 3 + g.below(30) as u32;
    let positions: Vec<[f64; 3]> = (0..nv)
        .map(|_| match g.below(25) {
            0 => [1e29, -1e29, 1e29],
            1 => [1e-29, 0.0, -1e-29],
            _ => [1000.0 * g.unit(), 1000.0 * g.unit(), 100.0 * g.unit()],
        })
        .collect();
    let nt = g.below(60) as u32;
    let triangles: Vec<[u32; 3]> = (0..nt)
        .map(|_| {
            [
                g.below(nv as u64) as u32,
                g.below(nv as u64) as u32,
                g.below(nv as u64) as u32,
            ]
        })
        .collect();
    let av0 = nt - g.below(u64::from(nt) / 3 + 1) as u32;
    let sectors = [1u32, 2, 3, 8, 16, 37, 1024][g.below(7) as usize];
    let mut nodes: Vec<Node> = Vec::new();
    fn make(g: &mut Rng, nodes: &mut Vec<Node>, range: [u32; 2], depth: u32, sectors: u32) -> (u32, u32) {
        let id = nodes.len() as u32;
        let regions = |g: &mut Rng| -> Vec<StoredRegion> {
            let mut out = Vec::new();
            if g.below(3) == 0 {
                return out;
            }
            for s in 0..sectors.min(1024) {
                if g.below(4) == 0 || (sectors > 64 && g.below(8) != 0) {
                    continue;
                }
                let k = 1 + g.below(4) as usize;
                let mut t = g.pick_f32(-100.0, 100.0);
                let mut points = Vec::new();
                for _ in 0..k {
                    points.push([t, g.pick_f32(-50.0, 200.0)]);
                    let step = 1.0 + 300.0 * g.unit() as f32;
                    let next = t + step;
                    if next <= t || !next.is_finite() {
                        break;
                    }
                    t = next;
                }
                out.push(StoredRegion {
                    sector: s as u16,
                    points,
                    tail_slope: g.pick_f32(-2.0, 2.0),
                });
            }
            out
        };
        let centre = [g.pick_f32(-1e4, 1e4), g.pick_f32(-1e4, 1e4)];
        let radius = g.pick_f32(0.0, 2000.0).abs();
        let r = regions(g);
        nodes.push(Node {
            centre,
            radius,
            children: vec![],
            triangles: range,
            level: 0,
            regions: r,
        });
        if depth == 0 || g.below(3) == 0 {
            return (id, 0);
        }
        let parts = 1 + g.below(4) as u32;
        let span = u64::from(range[1] - range[0]) + 1;
        let mut cuts: Vec<u32> = (0..parts - 1).map(|_| range[0] + g.below(span) as u32).collect();
        cuts.sort_unstable();
        let mut at = range[0];
        let mut kids = Vec::new();
        let mut level = 0;
        for c in cuts.into_iter().chain([range[1]]) {
            let (k, l) = make(g, nodes, [at, c], depth - 1, sectors);
            kids.push(k);
            level = level.max(l);
            at = c;
        }
        nodes[id as usize].children = kids;
        nodes[id as usize].level = level + 1 + g.below(3) as u32;
        (id, nodes[id as usize].level)
    }
    let mut roots = Vec::new();
    let mut at = 0;
    while at < av0 || (roots.is_empty() && g.below(2) == 0) {
        let end = (at + 1 + g.below(u64::from(av0 - at) + 1) as u32).min(av0);
        let depth = g.below(5) as u32;
        roots.push(make(g, &mut nodes, [at, end], depth, sectors).0);
        at = end;
    }
    let grouping = if g.below(2) == 0 {
        Grouping::Crystal
    } else {
        Grouping::Quadtree {
            built_depth: g.below(12) as u32,
            stored_depth: g.below(12) as u32,
        }
    };
    Hierarchy {
        sectors,
        origin: [g.unit() * 100.0, g.unit() * 100.0, 0.0],
        nodes,
        roots,
        always_visible: [av0, nt],
        mesh: Mesh { positions, triangles },
        build: BuildInfo {
            grouping,
            ..BuildInfo::default()
        },
    }
}

/// Random valid hierarchies through every method and random safe parameters: no panic, buffer protocol and
/// `max_ranges` hold, C equals Rust.
#[test]
fn attack_random_valid_hierarchies() {
    let mut g = Rng(0x9E37_79B9_7F4A_7C15);
    let (mut valid, mut invalid) = (0, 0);
    for round in 0..250 {
        let h = random_hierarchy(&mut g);
        if let Err(e) = h.check_invariants() {
            invalid += 1;
            if invalid < 5 {
                eprintln!("round {round}: generated an invalid one: {e}");
            }
            continue;
        }
        valid += 1;
        let label = format!("random {round}");
        check_all_methods(&h, &label);
        let bytes = h.to_bytes().expect("to_bytes");
        let c = load_bytes(&bytes, TC_METHOD_SAFE).expect("load");
        let mut d = TcParams::default();
        // SAFETY: valid pointers.
        unsafe { tc_default_params(&mut d) };
        let p = TcParams {
            columns_per_face: 1 << (1 + g.below(8)),
            patch: 1 + g.below(64) as u32,
            occluder_budget: [0, 1, 5, u32::MAX][g.below(4) as usize],
            work_budget: [0, 1, 3, 20, 1000, u32::MAX][g.below(6) as usize],
            coarse_columns: [0, 0, 1, 4, 1000][g.below(5) as usize],
        };
        // SAFETY: valid pointers.
        assert_eq!(unsafe { tc_set_params(c.0, &p) }, TC_OK, "{}", last_error());
        let sp = SafeParams {
            columns_per_face: p.columns_per_face as usize,
            patch: p.patch as usize,
            occluder_budget: if p.occluder_budget == u32::MAX {
                usize::MAX
            } else {
                p.occluder_budget as usize
            },
            work_budget: if p.work_budget == u32::MAX {
                usize::MAX
            } else {
                p.work_budget as usize
            },
            coarse_columns: p.coarse_columns as usize,
        };
        for (eye, yaw, fov) in cameras(&h).into_iter().step_by(2) {
            let got = c_cull(&c, eye, yaw, fov).expect("culls");
            assert_eq!(
                got,
                rust_cull(&h, TC_METHOD_SAFE, sp, eye, yaw, fov),
                "{label} {p:?} eye {eye:?}"
            );
            let mut w = TcWork::default();
            // SAFETY: valid pointers.
            unsafe { tc_work(c.0, &mut w) };
            assert!(w.work <= p.work_budget, "{label}: work {} over budget {p:?}", w.work);
        }
    }
    eprintln!("random hierarchies: {valid} valid, {invalid} invalid");
    assert!(valid > 60);
}

/// The mesh pointers stay valid and unchanged across culls and `tc_set_params`, and equal the hierarchy's arrays.
#[test]
fn attack_mesh_pointers_stable() {
    let h = grid_hierarchy(5, 8, false, Grouping::Crystal);
    let c = load_bytes(&h.to_bytes().expect("to_bytes"), TC_METHOD_SAFE).expect("load");
    let mut m0 = std::mem::MaybeUninit::<TcMesh>::zeroed();
    // SAFETY: valid pointers.
    unsafe {
        assert_eq!(tc_mesh(c.0, m0.as_mut_ptr()), TC_OK);
        let m0 = m0.assume_init();
        for (eye, yaw, fov) in cameras(&h) {
            c_cull(&c, eye, yaw, fov).expect("culls");
        }
        let mut d = TcParams::default();
        tc_default_params(&mut d);
        assert_eq!(
            tc_set_params(
                c.0,
                &TcParams {
                    columns_per_face: 8,
                    ..d
                }
            ),
            TC_OK
        );
        let mut m1 = std::mem::MaybeUninit::<TcMesh>::zeroed();
        assert_eq!(tc_mesh(c.0, m1.as_mut_ptr()), TC_OK);
        let m1 = m1.assume_init();
        assert_eq!((m0.positions, m0.indices), (m1.positions, m1.indices));
        let pos = std::slice::from_raw_parts(m0.positions, 3 * m0.vertices as usize);
        let flat: Vec<f64> = h.mesh.positions.iter().flatten().copied().collect();
        assert_eq!(pos, &flat[..]);
        let idx = std::slice::from_raw_parts(m0.indices, 3 * m0.triangles as usize);
        let flat: Vec<u32> = h.mesh.triangles.iter().flatten().copied().collect();
        assert_eq!(idx, &flat[..]);
    }
}

/// Separate cullers on separate threads at once give the serial results.
#[test]
fn attack_threads_with_separate_cullers() {
    let h = bundled(false);
    let bytes = h.to_bytes().expect("to_bytes");
    let eyes = cameras(h);
    let serial: Vec<Vec<[u32; 2]>> = {
        let c = load_bytes(&bytes, TC_METHOD_SAFE).expect("load");
        eyes.iter()
            .map(|&(e, y, f)| c_cull(&c, e, y, f).expect("culls"))
            .collect()
    };
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                let c = load_bytes(&bytes, TC_METHOD_SAFE).expect("load");
                for _ in 0..3 {
                    for (k, &(e, y, f)) in eyes.iter().enumerate() {
                        assert_eq!(c_cull(&c, e, y, f).expect("culls"), serial[k]);
                    }
                }
            });
        }
    });
}

/// A C program compiled with `-fsanitize=address,undefined` (when the compiler has them) drives every entry point
/// with NULLs, the two-call buffer protocol and a too-small buffer next to a guarded allocation, and loads damaged
/// files; it must exit 0 without a sanitizer report.
#[test]
fn attack_c_program_under_sanitizers() {
    let dir = tempfile::tempdir().expect("tempdir");
    let h = bundled(false);
    let tch_path = dir.path().join("t.tch");
    std::fs::write(&tch_path, h.to_bytes().expect("to_bytes")).expect("write");
    let src = dir.path().join("attack.c");
    std::fs::write(&src, C_SOURCE).expect("write C");
    let exe = dir.path().join("attack");
    let lib = static_lib();
    let mut cc = Command::new("cc");
    cc.arg(&src)
        .arg("-I")
        .arg(crate_dir().join("include"))
        .args([
            "-g",
            "-fsanitize=address,undefined",
            "-fno-sanitize-recover=all",
            "-Wall",
            "-Wextra",
            "-Werror",
        ])
        .arg(&lib)
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&exe);
    let out = cc.output().expect("cc runs");
    assert!(out.status.success(), "cc: {}", String::from_utf8_lossy(&out.stderr));
    let o = h.origin;
    let run = Command::new(&exe)
        .arg(&tch_path)
        .arg(format!("{}", o[0]))
        .arg(format!("{}", o[1]))
        .arg(format!("{}", o[2] + 300.0))
        .env("ASAN_OPTIONS", "detect_leaks=1:abort_on_error=0")
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success(),
        "exit {:?}\nstdout:\n{stdout}\nstderr:\n{stderr}",
        run.status
    );
    // The ranges the C program printed are the Rust API's.
    let eye = [o[0], o[1], o[2] + 300.0];
    for m in [TC_METHOD_SAFE, TC_METHOD_THESIS, TC_METHOD_LLOYD_EGBERT] {
        let want: Vec<String> = rust_cull(h, m, SafeParams::default(), eye, 30.0, 90.0)
            .iter()
            .map(|r| format!("{}-{}", r[0], r[1]))
            .collect();
        let line = format!("method {m}: {}", want.join(" "));
        assert!(
            stdout.lines().any(|l| l.trim_end() == line.trim_end()),
            "missing `{line}` in\n{stdout}"
        );
    }
}

fn static_lib() -> PathBuf {
    let exe = std::env::current_exe().expect("test path");
    let deps = exe.parent().expect("deps dir");
    for dir in [deps, deps.parent().expect("profile dir")] {
        let p = dir.join("libtincull_cull.a");
        if p.is_file() {
            return p;
        }
    }
    panic!("libtincull_cull.a not found near {}", deps.display());
}

const C_SOURCE: &str = r#"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include "tincull_cull.h"

#define CHECK(cond) do { if (!(cond)) { \
    fprintf(stderr, "FAIL line %d: %s (%s)\n", __LINE__, #cond, tc_last_error()); return 1; } } while (0)

int main(int argc, char **argv) {
    if (argc != 5) return 2;
    double eye[3] = { atof(argv[2]), atof(argv[3]), atof(argv[4]) };
    CHECK((tc_abi_version() >> 16) == (TC_ABI_VERSION >> 16));
    TcCuller *c = (TcCuller *)0x1;
    CHECK(tc_load_path(NULL, TC_METHOD_SAFE, &c) == TC_ERR_NULL && c == NULL);
    CHECK(tc_load_path("/nonexistent.tch", TC_METHOD_SAFE, &c) == TC_ERR_IO && c == NULL);
    CHECK(strlen(tc_last_error()) > 0);
    /* A damaged buffer in a heap block of exactly its size (ASan guards the bytes after it). */
    FILE *f = fopen(argv[1], "rb");
    CHECK(f != NULL);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *bytes = malloc((size_t)size);
    CHECK(fread(bytes, 1, (size_t)size, f) == (size_t)size);
    fclose(f);
    for (long cut = 0; cut < size; cut += (cut < 64 ? 1 : 997)) {
        unsigned char *part = malloc(cut ? (size_t)cut : 1);
        memcpy(part, bytes, (size_t)cut);
        c = (TcCuller *)0x1;
        CHECK(tc_load_buffer(part, (size_t)cut, TC_METHOD_SAFE, &c) == TC_ERR_FORMAT && c == NULL);
        free(part);
    }
    CHECK(tc_load_buffer(bytes, (size_t)-1, TC_METHOD_SAFE, &c) == TC_ERR_INVALID && c == NULL);
    CHECK(tc_load_buffer(bytes, (size_t)size, 99, &c) == TC_ERR_INVALID && c == NULL);
    CHECK(tc_load_buffer(bytes, (size_t)size, TC_METHOD_STEWART, &c) == TC_ERR_INVALID && c == NULL);
    uint32_t methods[3] = { TC_METHOD_SAFE, TC_METHOD_THESIS, TC_METHOD_LLOYD_EGBERT };
    for (int k = 0; k < 3; k++) {
        c = NULL;
        CHECK(tc_load_buffer(bytes, (size_t)size, methods[k], &c) == TC_OK && c != NULL);
        TcInfo info;
        CHECK(tc_info(c, &info) == TC_OK && info.method == methods[k]);
        TcMesh mesh;
        CHECK(tc_mesh(c, &mesh) == TC_OK);
        double sum = 0;
        for (uint32_t i = 0; i < 3 * mesh.vertices; i++) sum += mesh.positions[i];
        for (uint32_t i = 0; i < 3 * mesh.triangles; i++) CHECK(mesh.indices[i] < mesh.vertices);
        CHECK(isfinite(sum));
        size_t n = 0;
        CHECK(tc_cull(c, eye, 30.0, 90.0, NULL, 5, &n) == TC_ERR_NULL);
        int rc = tc_cull(c, eye, 30.0, 90.0, NULL, 0, &n);
        CHECK(rc == TC_OK || rc == TC_ERR_BUFFER_TOO_SMALL);
        CHECK(n <= info.max_ranges);
        /* A buffer of n - 1 elements, exactly allocated: nothing may be written. */
        if (n > 1) {
            TcRange *small = malloc((n - 1) * sizeof *small);
            size_t m = 0;
            CHECK(tc_cull(c, eye, 30.0, 90.0, small, n - 1, &m) == TC_ERR_BUFFER_TOO_SMALL && m == n);
            free(small);
        }
        TcRange *r = malloc((n ? n : 1) * sizeof *r);
        size_t m = 0;
        CHECK(tc_cull(c, eye, 30.0, 90.0, r, n, &m) == TC_OK && m == n);
        printf("method %u:", methods[k]);
        for (size_t i = 0; i < m; i++) printf(" %u-%u", r[i].start, r[i].end);
        printf("\n");
        double bad[3] = { eye[0], NAN, eye[2] };
        CHECK(tc_cull(c, bad, 30.0, 90.0, r, n, &m) == TC_ERR_INVALID);
        CHECK(tc_cull(c, eye, INFINITY, 90.0, r, n, &m) == TC_ERR_INVALID);
        CHECK(tc_cull(c, eye, 0.0, 0.0, r, n, &m) == TC_ERR_INVALID);
        free(r);
        TcStats st;
        CHECK(tc_stats(c, &st) == TC_OK && st.ranges == n);
        TcWork w;
        CHECK(tc_work(c, &w) == TC_OK);
        TcParams p;
        CHECK(tc_default_params(&p) == TC_OK);
        if (methods[k] == TC_METHOD_THESIS) {
            CHECK(tc_get_params(c, &p) == TC_ERR_INVALID);
        } else {
            CHECK(tc_get_params(c, &p) == TC_OK);
            p.columns_per_face = 3;
            CHECK(tc_set_params(c, &p) == TC_ERR_INVALID);
        }
        tc_free(c);
    }
    tc_free(NULL);
    free(bytes);
    return 0;
}
"#;
