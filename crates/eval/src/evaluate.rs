//! Evaluation of culling methods against ground truth (the README's "Accuracy: how it is measured").
//!
//! For each viewpoint class, viewpoints are drawn from the seeded generator; for each viewpoint the ground-truth
//! visible set `V` is computed once (exact segment walks; a lower bound of the true `V`, see [`truth::visible`]), and
//! every method's drawn set is scored against it. Methods:
//!
//! | method | what it draws |
//! | --- | --- |
//! | `safe` | the safe culler over the `.tch` hierarchy (`cull::SafeCuller`; never culls a visible triangle) |
//! | `safe_regions` | the thesis' run-time test over conservative precomputed regions (`pipeline::conservative_hierarchy`; never culls a visible triangle) |
//! | `thesis` | the thesis' recursive region test over the `.tch` hierarchy (`cull::Culler`; not conservative) |
//! | `per_triangle` | each triangle tested against its own regions (thesis 5.1.1) |
//! | `frustum_only` | the hierarchy's frustum test alone (everything at a 360° field of view) |
//! | `none` | every triangle |
//!
//! With a field of view below 360°, each viewpoint gets a yaw from the generator, and `V` is restricted to the
//! triangles that meet the horizontal view wedge in x,y (`truth::in_view`): a triangle wholly outside the view is
//! not counted as a false cull when culled, one partly inside is.
//!
//! Per viewpoint, besides the methods' metrics: `visible_fraction` (`|V| / |A|`) and `leaf_limit`, the occlusion
//! captured by culling exactly the hierarchy's leaves that hold no visible triangle (orphans never): the best any
//! test over this hierarchy's leaves can do.

use std::f64::consts::TAU;
use std::time::Instant;

use anyhow::Result;
use cull::{AnyCuller, Camera, CullMethod, Culler, DrawList, Hierarchy, SafeParams};
use glam::DVec3;
use horizon::{HorizonOptions, SectorConfig};
use occlusion::RegionTable;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use tin::Tin;
use truth::{GroundTruth, Summary, ViewMetrics, ViewpointClass, summarize, view_metrics};

use pipeline::{per_triangle_hierarchy, triangle_regions};

/// The methods an evaluation compares, in report order. The region test of a hierarchy is named `thesis` over crystal
/// groups and `stewart` over a quadtree ([`CullMethod::regions_for`]).
pub const METHODS: [&str; 8] = [
    "safe",
    "lloyd-egbert",
    "safe_regions",
    "thesis",
    "stewart",
    "per_triangle",
    "frustum_only",
    "none",
];

/// Most viewpoints per class: each one's ground truth takes milliseconds or more, and all are kept in memory.
pub const MAX_VIEWPOINTS: usize = 1_000_000;

/// What to evaluate. Serialized as it applies: with `eyes`, `viewpoints` and `classes` are `null` (they are not used)
/// and `eyes` is their count (the eyes themselves are the viewpoints' `eye`); without, `eyes` is `null`.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalOptions {
    /// Viewpoints per class.
    pub viewpoints: usize,
    /// Classes to draw viewpoints from.
    pub classes: Vec<ViewpointClass>,
    /// Seed of the viewpoint generator (`--view-seed`; `rng_seed` seeds the grouping, elsewhere).
    pub view_seed: u64,
    /// Horizontal field of view in degrees (360 = all around, the thesis' measurement mode).
    pub fov_deg: f64,
    /// Also evaluate the per-triangle method (needs the horizons of the mesh again).
    pub per_triangle: bool,
    /// Parameters of the safe culler.
    pub safe: SafeParams,
    /// Also evaluate the thesis' test over conservative precomputed regions (computes them first).
    pub safe_regions: bool,
    /// Score these eyes (class `path`, a user's camera path) instead of drawing viewpoints from `classes`.
    pub eyes: Option<Vec<[f64; 3]>>,
}

impl Serialize for EvalOptions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        /// The options as they apply (see [`EvalOptions`]).
        #[derive(Serialize)]
        struct Applied<'a> {
            viewpoints: Option<usize>,
            classes: Option<&'a [ViewpointClass]>,
            view_seed: u64,
            fov_deg: f64,
            per_triangle: bool,
            safe: SafeParams,
            safe_regions: bool,
            eyes: Option<usize>,
        }
        let classes = self.eyes.is_none();
        Applied {
            viewpoints: classes.then_some(self.viewpoints),
            classes: classes.then_some(&self.classes[..]),
            view_seed: self.view_seed,
            fov_deg: self.fov_deg,
            per_triangle: self.per_triangle,
            safe: self.safe,
            safe_regions: self.safe_regions,
            eyes: self.eyes.as_ref().map(Vec::len),
        }
        .serialize(s)
    }
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            viewpoints: 20,
            classes: ViewpointClass::ALL.to_vec(),
            view_seed: 1,
            fov_deg: 360.0,
            per_triangle: true,
            safe: SafeParams::default(),
            safe_regions: true,
            eyes: None,
        }
    }
}

/// One method on one viewpoint class.
#[derive(Clone, Debug, Serialize)]
pub struct EvalRow {
    /// Method name (see [`METHODS`]).
    pub method: String,
    /// Viewpoint class.
    pub class: String,
    /// Aggregated metrics.
    pub summary: Summary,
    /// Median run-time test time over the viewpoints (ns).
    pub cull_ns: u64,
    /// Mean `|V| / |A|` over the viewpoints.
    pub visible_fraction: f64,
    /// Mean `|D| / |A|` over the viewpoints.
    pub drawn_fraction: f64,
    /// Mean leaf limit over the viewpoints where something is hidden (`None` without a hierarchy or when nothing is
    /// hidden anywhere).
    pub leaf_limit: Option<f64>,
}

/// One viewpoint's ground truth and scores, for tools that chart individual viewpoints.
#[derive(Clone, Debug, Serialize)]
pub struct ViewpointResult {
    /// Class of the viewpoint.
    pub class: String,
    /// Eye position.
    pub eye: [f64; 3],
    /// View direction (degrees), when the field of view is below 360°.
    pub yaw_deg: Option<f64>,
    /// Per method, in [`METHODS`] order (methods not evaluated are left out): its name, its metrics, and its cull
    /// time in nanoseconds (in the exported JSON, the third element of each `[name, metrics, ns]`).
    pub methods: Vec<(String, ViewMetrics, u64)>,
    /// `|V| / |A|`.
    pub visible_fraction: f64,
    /// The leaf limit of the scored hierarchy from this viewpoint (`None` without one, or when nothing is hidden).
    pub leaf_limit: Option<f64>,
}

/// The whole evaluation.
#[derive(Clone, Debug, Serialize)]
pub struct Evaluation {
    /// Options used.
    pub options: EvalOptions,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Rows per method and class, then per method over all classes (class `all`).
    pub rows: Vec<EvalRow>,
    /// Every viewpoint.
    pub viewpoints: Vec<ViewpointResult>,
    /// Seconds of ground truth per viewpoint (mean).
    pub ground_truth_seconds_per_viewpoint: f64,
    /// Seconds to prepare the per-triangle regions (0 when not evaluated).
    pub per_triangle_setup_seconds: f64,
    /// Seconds to compute the conservative regions of `safe_regions` (0 when not evaluated).
    pub safe_regions_setup_seconds: f64,
}

/// Times `cull_into` for one camera: the median of 15 runs after a warm-up, in nanoseconds. The result is left in
/// `out`.
pub fn timed_cull(culler: &AnyCuller, camera: &Camera, out: &mut DrawList) -> u64 {
    const RUNS: usize = 15;
    culler.cull_into(camera, out);
    let mut times = [0u64; RUNS];
    for t in &mut times {
        let start = Instant::now();
        culler.cull_into(camera, out);
        *t = start.elapsed().as_nanos() as u64;
    }
    times.sort_unstable();
    times[RUNS / 2]
}

/// The mesh of a hierarchy as a [`Tin`], triangles in hierarchy order.
pub fn hierarchy_tin(h: &Hierarchy) -> Result<Tin> {
    let positions = h.mesh.positions.iter().map(|&p| DVec3::from_array(p)).collect();
    Ok(Tin::from_parts(positions, h.mesh.triangles.clone())?)
}

/// The per-triangle hierarchy of `h`'s mesh, recomputing horizons and regions with `h`'s sector configuration.
pub fn per_triangle_of(h: &Hierarchy, tin: &Tin) -> Result<Hierarchy> {
    let config = SectorConfig::new(h.sectors, h.build.subsectors.max(1))?;
    let opts = HorizonOptions {
        undersampling_radius: h.build.undersampling,
        progress: None,
    };
    let field = horizon::compute(tin, &config, &opts)?;
    let vertices = RegionTable::from_field(tin.positions(), &field);
    Ok(per_triangle_hierarchy(tin, &triangle_regions(tin, &vertices)))
}

/// One viewpoint of a [`GroundTruthSet`].
#[derive(Clone, Debug)]
pub struct TruthView {
    /// Class the viewpoint was drawn from.
    pub class: ViewpointClass,
    /// Eye position.
    pub eye: DVec3,
    /// View direction (radians; 0 when the field of view is 360°).
    pub yaw: f64,
    /// Ground-truth visible set restricted to the view wedge, one flag per triangle of the TIN it was computed on.
    pub visible: Vec<bool>,
}

/// The ground truth of every viewpoint of an evaluation over one TIN, in that TIN's triangle order.
///
/// It depends only on the mesh and the viewpoint options (classes, count, seed, field of view), never on the build
/// parameters, so a parameter sweep computes it once and scores every build against it (see [`score`], whose
/// methods may draw in another triangle order).
#[derive(Clone, Debug)]
pub struct GroundTruthSet {
    /// Options the viewpoints were drawn with.
    pub options: EvalOptions,
    /// Triangles of the TIN.
    pub triangles: usize,
    /// Every viewpoint, class by class in the options' order.
    pub views: Vec<TruthView>,
    /// Seconds of ground truth per viewpoint (mean).
    pub seconds_per_viewpoint: f64,
}

impl GroundTruthSet {
    /// Draws the viewpoints of `opts` over `tin` and computes their visible sets. `progress` is called after each
    /// viewpoint with `(done, total)`.
    pub fn compute(tin: &Tin, opts: &EvalOptions, progress: &dyn Fn(usize, usize)) -> Result<GroundTruthSet> {
        anyhow::ensure!(
            opts.fov_deg > 0.0 && opts.fov_deg <= 360.0,
            "the field of view must be in (0, 360] degrees, got {}",
            tin::compact_number(opts.fov_deg)
        );
        anyhow::ensure!(!opts.classes.is_empty(), "no viewpoint classes");
        anyhow::ensure!(
            opts.viewpoints <= MAX_VIEWPOINTS,
            "{} viewpoints per class: at most {MAX_VIEWPOINTS}",
            opts.viewpoints
        );
        let truth = GroundTruth::new(tin);
        let all_around = opts.fov_deg >= 360.0;
        let groups: Vec<(ViewpointClass, Vec<DVec3>, u64)> = match &opts.eyes {
            Some(eyes) => {
                anyhow::ensure!(!eyes.is_empty(), "no eyes to score");
                vec![(
                    ViewpointClass::Path,
                    eyes.iter().map(|&e| DVec3::from_array(e)).collect(),
                    opts.view_seed,
                )]
            }
            None => opts
                .classes
                .iter()
                .map(|&class| {
                    // Seeded by the class itself, not its place in `classes`: a class gets the same eyes whichever
                    // other classes are asked for.
                    let ci = ViewpointClass::ALL
                        .iter()
                        .position(|&c| c == class)
                        .unwrap_or(ViewpointClass::ALL.len());
                    let seed = opts
                        .view_seed
                        .wrapping_mul(0x9e37_79b9_7f4a_7c15)
                        .wrapping_add(ci as u64);
                    (class, truth::viewpoints(tin, class, opts.viewpoints, seed), seed)
                })
                .collect(),
        };
        let total: usize = groups.iter().map(|g| g.1.len()).sum();
        let mut views = Vec::with_capacity(total);
        let mut truth_seconds = 0.0;
        for (class, eyes, seed) in groups {
            let mut yaw_rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
            for eye in eyes {
                let yaw = if all_around {
                    0.0
                } else {
                    yaw_rng.random_range(0.0..TAU)
                };
                let t0 = Instant::now();
                let mut visible = truth.visible_triangles(eye);
                truth_seconds += t0.elapsed().as_secs_f64();
                if !all_around {
                    let view = truth::in_view(tin, eye, yaw, opts.fov_deg.to_radians() * 0.5);
                    visible.iter_mut().zip(view).for_each(|(v, inside)| *v &= inside);
                }
                views.push(TruthView {
                    class,
                    eye,
                    yaw,
                    visible,
                });
                progress(views.len(), total);
            }
        }
        Ok(GroundTruthSet {
            options: opts.clone(),
            triangles: tin.num_triangles(),
            seconds_per_viewpoint: truth_seconds / views.len().max(1) as f64,
            views,
        })
    }
}

/// A culling method to score with [`score`].
pub struct Method<'a> {
    /// Name (see [`METHODS`]).
    pub name: &'a str,
    /// The culler; `None` draws every triangle.
    pub culler: Option<AnyCuller>,
    /// Where each of the culler's triangles is in the scored TIN: triangle `i` of the culler's mesh is triangle
    /// `order[i]` of the TIN (a build's `crystal.order`). `None`: the same order.
    pub order: Option<&'a [u32]>,
    /// The eyes the method judges, for one whose height margin is fixed when it is prepared (`safe_regions`): from an
    /// eye it does not cover, everything is drawn. `None`: every eye.
    pub reach: Option<truth::MarginReach>,
}

/// The eyes from which the conservative regions of `h` ([`pipeline::conservative_hierarchy`]) may be judged: those
/// their height margin covers (`truth::MarginReach`).
pub fn conservative_reach(h: &Hierarchy) -> truth::MarginReach {
    let (mu, lo, hi) = pipeline::conservative_margin(h);
    truth::MarginReach::new(mu, lo, hi)
}

/// The hierarchy's frustum test alone: `h` with every region removed.
pub fn frustum_only(h: &Hierarchy) -> Hierarchy {
    let mut f = h.clone();
    for n in &mut f.nodes {
        n.regions.clear();
    }
    f
}

/// The names of the methods [`standard_methods`] gives, in [`METHODS`] order: the region test is `stewart` for a
/// quadtree build and `thesis` otherwise, and `per_triangle` is scored only when asked for. [`score`] writes one row
/// per name and class, in this order.
pub fn standard_method_names(quadtree: bool, per_triangle: bool) -> Vec<&'static str> {
    let regions = if quadtree {
        CullMethod::Stewart
    } else {
        CullMethod::Thesis
    };
    let mut names = vec![CullMethod::Safe.name(), CullMethod::LloydEgbert.name(), regions.name()];
    if per_triangle {
        names.push("per_triangle");
    }
    names.extend(["frustum_only", "none"]);
    names
}

/// The methods of [`METHODS`] for a hierarchy `h` whose triangle `i` is triangle `order[i]` of the scored TIN
/// (`None`: same order), and an optional per-triangle hierarchy in the TIN's own order.
pub fn standard_methods<'a>(
    h: &Hierarchy,
    per_triangle: Option<&Hierarchy>,
    order: Option<&'a [u32]>,
    safe: SafeParams,
) -> Vec<Method<'a>> {
    vec![
        Method {
            name: "safe",
            culler: Some(AnyCuller::with_params(h, CullMethod::Safe, safe)),
            order,
            reach: None,
        },
        Method {
            name: CullMethod::LloydEgbert.name(),
            culler: Some(AnyCuller::with_params(h, CullMethod::LloydEgbert, safe)),
            order,
            reach: None,
        },
        Method {
            name: CullMethod::regions_for(h).name(),
            culler: Some(AnyCuller::new(h, CullMethod::regions_for(h))),
            order,
            reach: None,
        },
        Method {
            name: "per_triangle",
            culler: per_triangle.map(|p| AnyCuller::Thesis(Culler::new(p))),
            order: None,
            reach: None,
        },
        Method {
            name: "frustum_only",
            culler: Some(AnyCuller::Thesis(Culler::new(&frustum_only(h)))),
            order,
            reach: None,
        },
        Method {
            name: "none",
            culler: None,
            order: None,
            reach: None,
        },
    ]
}

/// The leaves of a hierarchy for the leaf limit: their triangle ranges in the hierarchy's order, and where each of
/// its triangles is in the scored TIN (`None`: the same order).
#[derive(Clone, Copy, Debug)]
pub struct Leaves<'a> {
    /// `[start, end)` of every leaf group.
    pub ranges: &'a [[u32; 2]],
    /// `order[i]`: the TIN triangle of the hierarchy's triangle `i`.
    pub order: Option<&'a [u32]>,
}

/// The leaf limit: the occlusion captured by culling exactly the leaves without a visible triangle (`visible` in the
/// TIN's order); `None` when nothing is hidden.
pub fn leaf_limit(visible: &[bool], leaves: Leaves) -> Option<f64> {
    let hidden = visible.iter().filter(|&&v| !v).count();
    if hidden == 0 {
        return None;
    }
    let tin_of = |i: u32| leaves.order.map_or(i, |o| o[i as usize]) as usize;
    let culled: usize = leaves
        .ranges
        .iter()
        .filter(|r| (r[0]..r[1]).all(|i| !visible[tin_of(i)]))
        .map(|r| (r[1] - r[0]) as usize)
        .sum();
    Some(culled as f64 / hidden as f64)
}

/// Scores `methods` against the ground truth `truth` of `tin` (every mask in `tin`'s triangle order). A method named
/// other than `none` without a culler is left out (e.g. `per_triangle` when not evaluated). `leaves`, when given,
/// gives every viewpoint its leaf limit.
pub fn score(tin: &Tin, truth: &GroundTruthSet, methods: &[Method], leaves: Option<Leaves>) -> Result<Evaluation> {
    let n = tin.num_triangles();
    anyhow::ensure!(
        truth.triangles == n,
        "the ground truth has {} triangles, the mesh {n}",
        truth.triangles
    );
    for m in methods {
        if let Some(order) = m.order {
            anyhow::ensure!(
                order.len() == n && order.iter().all(|&t| (t as usize) < n),
                "method {}: its triangle order does not map onto the mesh's {n} triangles",
                m.name
            );
        }
    }
    let opts = &truth.options;
    let all_around = opts.fov_deg >= 360.0;
    let mut list = DrawList::default();
    let mut results = Vec::with_capacity(truth.views.len());
    let ordered = methods_in_order(methods);
    for view in &truth.views {
        let camera = Camera {
            position: view.eye.to_array(),
            yaw: view.yaw,
            hfov: if all_around { TAU } else { opts.fov_deg.to_radians() },
        };
        let mut methods = Vec::new();
        for m in &ordered {
            let (drawn, ns) = match &m.culler {
                // A method judges only the eyes its margin covers; from the others it draws everything.
                Some(_) if m.reach.is_some_and(|r| !r.covers(camera.position, camera.position)) => (vec![true; n], 0),
                Some(c) => {
                    let ns = timed_cull(c, &camera, &mut list);
                    let mask = list.mask(n);
                    let drawn = match m.order {
                        Some(order) => {
                            let mut d = vec![false; n];
                            for (i, &t) in order.iter().enumerate() {
                                d[t as usize] = mask[i];
                            }
                            d
                        }
                        None => mask,
                    };
                    (drawn, ns)
                }
                None if m.name == "none" => (vec![true; n], 0),
                None => continue,
            };
            methods.push((m.name.to_string(), view_metrics(tin, &view.visible, &drawn)?, ns));
        }
        results.push(ViewpointResult {
            class: view.class.name().to_string(),
            eye: view.eye.to_array(),
            yaw_deg: (!all_around).then(|| view.yaw.to_degrees()),
            methods,
            visible_fraction: view.visible.iter().filter(|&&v| v).count() as f64 / n.max(1) as f64,
            leaf_limit: leaves.and_then(|l| leaf_limit(&view.visible, l)),
        });
    }
    let mut rows = Vec::new();
    let classes: Vec<String> = match opts.eyes {
        Some(_) => vec![ViewpointClass::Path.name().to_string()],
        None => opts
            .classes
            .iter()
            .map(|c| c.name().to_string())
            .chain(["all".into()])
            .collect(),
    };
    for name in METHODS {
        for class in &classes {
            let views: Vec<&ViewpointResult> = results
                .iter()
                .filter(|r| (class == "all" || &r.class == class) && r.methods.iter().any(|m| m.0 == name))
                .collect();
            let picked: Vec<(&ViewMetrics, u64)> = views
                .iter()
                .flat_map(|r| r.methods.iter().filter(|m| m.0 == name).map(|m| (&m.1, m.2)))
                .collect();
            if picked.is_empty() {
                continue;
            }
            let mean = |xs: &mut dyn Iterator<Item = f64>| {
                let (sum, count) = xs.fold((0.0, 0usize), |(s, c), x| (s + x, c + 1));
                (count > 0).then(|| sum / count as f64)
            };
            let visible_fraction = mean(&mut views.iter().map(|r| r.visible_fraction)).unwrap_or(0.0);
            let leaf_limit_mean = mean(&mut views.iter().filter_map(|r| r.leaf_limit));
            let drawn_fraction = mean(
                &mut picked
                    .iter()
                    .map(|(m, _)| m.triangles_drawn as f64 / m.triangles.max(1) as f64),
            )
            .unwrap_or(0.0);
            let metrics: Vec<ViewMetrics> = picked.iter().map(|(m, _)| (*m).clone()).collect();
            let mut ns: Vec<u64> = picked.iter().map(|p| p.1).collect();
            ns.sort_unstable();
            rows.push(EvalRow {
                method: name.to_string(),
                class: class.clone(),
                summary: summarize(&metrics),
                cull_ns: ns[ns.len() / 2],
                visible_fraction,
                drawn_fraction,
                leaf_limit: leaf_limit_mean,
            });
        }
    }
    Ok(Evaluation {
        options: opts.clone(),
        triangles: n,
        rows,
        ground_truth_seconds_per_viewpoint: truth.seconds_per_viewpoint,
        viewpoints: results,
        per_triangle_setup_seconds: 0.0,
        safe_regions_setup_seconds: 0.0,
    })
}

/// `methods` in [`METHODS`] order (unknown names last, in their given order).
fn methods_in_order<'m, 'a>(methods: &'m [Method<'a>]) -> Vec<&'m Method<'a>> {
    let mut v: Vec<&Method> = methods.iter().collect();
    v.sort_by_key(|m| METHODS.iter().position(|&n| n == m.name).unwrap_or(METHODS.len()));
    v
}

/// Evaluates `h` (whose mesh is `tin`) from the viewpoints of `opts`. `progress` is called after each viewpoint's
/// ground truth.
pub fn evaluate(h: &Hierarchy, tin: &Tin, opts: &EvalOptions, progress: &dyn Fn(usize, usize)) -> Result<Evaluation> {
    anyhow::ensure!(
        opts.fov_deg > 0.0 && opts.fov_deg <= 360.0,
        "the field of view must be in (0, 360] degrees"
    );
    anyhow::ensure!(!opts.classes.is_empty(), "no viewpoint classes");
    let start = Instant::now();
    let per_triangle = if opts.per_triangle {
        Some(per_triangle_of(h, tin)?)
    } else {
        None
    };
    let per_triangle_setup_seconds = if opts.per_triangle {
        start.elapsed().as_secs_f64()
    } else {
        0.0
    };
    let truth = GroundTruthSet::compute(tin, opts, progress)?;
    let mut methods = standard_methods(h, per_triangle.as_ref(), None, opts.safe);
    let start = Instant::now();
    if opts.safe_regions {
        methods.push(Method {
            name: "safe_regions",
            culler: Some(AnyCuller::Thesis(Culler::new(&pipeline::conservative_hierarchy(h)))),
            order: None,
            reach: Some(conservative_reach(h)),
        });
    }
    let safe_regions_setup_seconds = if opts.safe_regions {
        start.elapsed().as_secs_f64()
    } else {
        0.0
    };
    let ranges = h.leaf_ranges();
    let leaves = Leaves {
        ranges: &ranges,
        order: None,
    };
    let mut e = score(tin, &truth, &methods, Some(leaves))?;
    e.per_triangle_setup_seconds = per_triangle_setup_seconds;
    e.safe_regions_setup_seconds = safe_regions_setup_seconds;
    Ok(e)
}

impl Evaluation {
    /// The CSV form: one line per method and class.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "method,class,viewpoints,viewpoints_with_false_culls,false_culls_mean,false_culls_max,\
             false_cull_area_mean,false_cull_area_max,occlusion_captured_mean,occlusion_captured_p50,\
             occlusion_captured_p95,overdraw_mean,triangles_drawn_mean,cull_ns,visible_fraction,drawn_fraction,\
             leaf_limit\n",
        );
        let f = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x}"));
        for r in &self.rows {
            let m = &r.summary;
            s += &format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                r.method,
                r.class,
                m.viewpoints,
                m.viewpoints_with_false_culls,
                f(m.false_culls.map(|x| x.mean)),
                f(m.false_culls.map(|x| x.max)),
                f(m.false_cull_area.map(|x| x.mean)),
                f(m.false_cull_area.map(|x| x.max)),
                f(m.occlusion_captured.map(|x| x.mean)),
                f(m.occlusion_captured.map(|x| x.p50)),
                f(m.occlusion_captured.map(|x| x.p95)),
                f(m.overdraw.map(|x| x.mean)),
                f(m.triangles_drawn.map(|x| x.mean)),
                r.cull_ns,
                r.visible_fraction,
                r.drawn_fraction,
                f(r.leaf_limit)
            );
        }
        s
    }

    /// A readable table: per method and class, false culls, occlusion captured, overdraw, drawn, cull time.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<13} {:<7} {:>4} {:>10} {:>8} {:>9} {:>10} {:>8} {:>8} {:>9} {:>9}\n",
            "method",
            "class",
            "n",
            "false_cull",
            "fc_views",
            "occl_capt",
            "leaf_limit",
            "visible",
            "drawn",
            "overdraw",
            "cull_µs"
        );
        for r in &self.rows {
            let m = &r.summary;
            let mean = |x: Option<truth::Stat>| x.map_or("-".to_string(), |x| format!("{:.3}", x.mean));
            s += &format!(
                "{:<13} {:<7} {:>4} {:>10} {:>8} {:>9} {:>10} {:>7.1}% {:>7.1}% {:>9} {:>9.2}\n",
                r.method,
                r.class,
                m.viewpoints,
                m.false_culls.map_or("-".to_string(), |x| format!("{:.1}", x.mean)),
                m.viewpoints_with_false_culls,
                mean(m.occlusion_captured),
                r.leaf_limit.map_or("-".to_string(), |x| format!("{x:.3}")),
                100.0 * r.visible_fraction,
                100.0 * r.drawn_fraction,
                mean(m.overdraw),
                r.cull_ns as f64 / 1000.0
            );
        }
        s
    }
}
