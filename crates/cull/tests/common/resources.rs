//! What the resource attacks share (`resource_attacks.rs` in `crates/cull`, `crates/pipeline` and `crates/pvs`, which
//! include this file by path): a counting allocator for the test binary, a measurement under a lock, and the crafted
//! hierarchies (grids of squares, chains of nodes of one child each over one range).

// Each test binary uses its own subset of these.
#![allow(dead_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use cull::{Hierarchy, Mesh, Node};

/// Counts the bytes live, the most live since the last [`measure`], and the bytes allocated in all.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static TOTAL: AtomicUsize = AtomicUsize::new(0);

fn grew(by: usize) {
    let now = LIVE.fetch_add(by, Ordering::Relaxed) + by;
    PEAK.fetch_max(now, Ordering::Relaxed);
    TOTAL.fetch_add(by, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                grew(new_size - layout.size());
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// One measurement at a time: the counters are global, and the printed timings should not share the cores.
static SERIAL: Mutex<()> = Mutex::new(());

/// Takes the measurement lock (every test of a resource-attack binary holds it throughout).
pub fn lock() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// What [`measure`] saw: the time taken (printed, never asserted: the machines are shared), the most bytes live at
/// once beyond those live before, and the bytes allocated in all.
#[derive(Clone, Copy, Debug)]
pub struct Usage {
    pub took: Duration,
    pub peak: usize,
    pub total: usize,
}

/// Runs `f`, returning its value and what it used.
pub fn measure<T>(f: impl FnOnce() -> T) -> (T, Usage) {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let total = TOTAL.load(Ordering::Relaxed);
    let start = Instant::now();
    let out = f();
    let took = start.elapsed();
    let usage = Usage {
        took,
        peak: PEAK.load(Ordering::Relaxed).saturating_sub(base),
        total: TOTAL.load(Ordering::Relaxed) - total,
    };
    (out, usage)
}

pub const MB: usize = 1 << 20;

/// A grid terrain of `n` × `n` squares (two triangles each) over `[0, n]²`, heights a gentle bowl with ripples,
/// triangles row by row (so that a halving of the order is a split into bands).
pub fn grid_mesh(n: u32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (f64::from(i), f64::from(j));
            let c = f64::from(n) * 0.5;
            let z = 0.01 * ((x - c).powi(2) + (y - c).powi(2)) + (x * 0.7).sin() + (y * 1.3).cos();
            positions.push([x, y, z]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            triangles.push([v, v + 1, v + n + 2]);
            triangles.push([v, v + n + 2, v + n + 1]);
        }
    }
    Mesh { positions, triangles }
}

/// A node with the circle 0 (which misses its vertices: the cullers and the conservative regions compute their own)
/// and no regions.
pub fn node(children: Vec<u32>, triangles: [u32; 2], level: u32) -> Node {
    Node {
        centre: [0.0; 2],
        radius: 0.0,
        children,
        triangles,
        level,
        regions: vec![],
    }
}

/// The hierarchy of `nodes` over `mesh` with `sectors` sectors and no always-visible triangle, checked.
pub fn hierarchy_of(mesh: Mesh, nodes: Vec<Node>, roots: Vec<u32>, sectors: u32) -> Hierarchy {
    let nt = mesh.triangles.len() as u32;
    let h = Hierarchy {
        sectors,
        origin: [0.0; 3],
        nodes,
        roots,
        always_visible: [nt, nt],
        mesh,
        build: Default::default(),
    };
    h.check_invariants().expect("a valid hierarchy");
    h
}

/// [`hierarchy_of`] with 16 sectors.
pub fn hierarchy(mesh: Mesh, nodes: Vec<Node>, roots: Vec<u32>) -> Hierarchy {
    hierarchy_of(mesh, nodes, roots, 16)
}

/// `depth` nodes with one child each above one leaf, all over the triangles `range`; the triangles before and after
/// it (if any) are two more root leaves, after the chain. `sectors` sectors.
pub fn chain_over(mesh: Mesh, range: [u32; 2], depth: u32, sectors: u32) -> Hierarchy {
    let nt = mesh.triangles.len() as u32;
    let mut nodes = vec![node(vec![], range, 0)];
    for l in 1..=depth {
        nodes.push(node(vec![l - 1], range, l));
    }
    let mut roots = vec![depth];
    for rest in [[0, range[0]], [range[1], nt]] {
        if rest[0] < rest[1] {
            roots.push(nodes.len() as u32);
            nodes.push(node(vec![], rest, 0));
        }
    }
    hierarchy_of(mesh, nodes, roots, sectors)
}

/// A chain of `depth` nodes of one child each over one leaf holding every triangle of `mesh`: as deep as it has
/// nodes, every node over the same range.
pub fn chain(mesh: Mesh, depth: u32) -> Hierarchy {
    let nt = mesh.triangles.len() as u32;
    chain_over(mesh, [0, nt], depth, 16)
}

/// Leaves of `leaf` triangles each over `mesh`, all roots.
pub fn flat(mesh: Mesh, leaf: u32) -> Hierarchy {
    let nt = mesh.triangles.len() as u32;
    let nodes: Vec<Node> = (0..nt.div_ceil(leaf))
        .map(|i| node(vec![], [i * leaf, ((i + 1) * leaf).min(nt)], 0))
        .collect();
    let roots = (0..nodes.len() as u32).collect();
    hierarchy(mesh, nodes, roots)
}

/// Runs `f` on a thread with a 256 KiB stack: an operation recursive over the depth of a hierarchy of 100,000 levels
/// would overflow it (and abort the test binary).
pub fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(256 << 10)
        .spawn(f)
        .expect("a thread")
        .join()
        .expect("no panic")
}
