//! The run-time culling methods behind one interface, chosen by name (`--method` on the command line).
//!
//! `thesis` and `stewart` are the same test — one region test per node, over the sectors that the node's bounding
//! circle spans from the camera ([`Culler`]) — meant for different groupings: `thesis` for crystal hierarchies,
//! `stewart` for quadtree ones (Stewart 1997, §5.3 and §5.4; [`Grouping`]). [`CullMethod::check`] refuses the
//! other pairing, so that a report's method name always says which hierarchy was culled. `safe` works on both, and
//! so does `lloyd-egbert` ([`LloydEgbertCuller`]): Lloyd & Egbert's method is meant for a quadtree, whose leaf cells
//! give its occluder grid, but its verdicts do not depend on the grid, so over a crystal hierarchy it uses a grid
//! with about as many cells as leaf groups.
//!
//! Stewart takes the sector range from the four corners of the quad (§5.3): the directions from the quad's points to
//! the camera lie between those from its corners. A node's triangles are those whose centroid lies in the cell, so
//! they stick out of it; the bounding circle of all their vertices contains them, and the azimuth interval it spans
//! (`± asin(radius / distance)`) contains every direction from them to the camera. It touches at least the sectors
//! that the corners of the triangles' bounding box would give, so it may test more sectors (cull less), never fewer;
//! a camera inside the circle sees the node, where Stewart's rule would still test a camera just outside the quad.

use crate::culler::{Camera, Culler, DrawList};
use crate::error::HierarchyError;
use crate::hierarchy::{Grouping, Hierarchy};
use crate::lloyd_egbert::LloydEgbertCuller;
use crate::safe::{SafeCuller, SafeParams};

/// A run-time culling method over a [`Hierarchy`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CullMethod {
    /// [`SafeCuller`]: front to back against a conservative horizon; never culls a visible triangle (the default).
    #[default]
    Safe,
    /// [`Culler`]: the thesis' test of the camera against each node's precomputed sector regions (not conservative),
    /// over a crystal hierarchy.
    Thesis,
    /// [`Culler`] over a quadtree hierarchy: Stewart's hierarchical visibility (1997, §5.3–5.4), one region test per
    /// cell, cells without stored regions visible (not conservative either).
    Stewart,
    /// [`LloydEgbertCuller`]: Lloyd & Egbert's (2002) run-time horizon culling, cell edges as occluders and node
    /// boxes as occludees over the same conservative horizon; never culls a visible triangle.
    LloydEgbert,
}

impl CullMethod {
    /// Every method, the default first.
    pub const ALL: [CullMethod; 4] = [
        CullMethod::Safe,
        CullMethod::Thesis,
        CullMethod::Stewart,
        CullMethod::LloydEgbert,
    ];

    /// The method's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            CullMethod::Safe => "safe",
            CullMethod::Thesis => "thesis",
            CullMethod::Stewart => "stewart",
            CullMethod::LloydEgbert => "lloyd-egbert",
        }
    }

    /// Whether the method applies to `h`: `thesis` needs a crystal hierarchy and `stewart` a quadtree one (see the
    /// module documentation); `safe` and `lloyd-egbert` take both.
    pub fn check(self, h: &Hierarchy) -> Result<(), HierarchyError> {
        self.check_grouping(h.build.grouping)
    }

    /// [`CullMethod::check`] for a hierarchy of `grouping`, before it is built.
    pub fn check_grouping(self, grouping: Grouping) -> Result<(), HierarchyError> {
        let wrong = |needs: &str, build: &str| {
            Err(HierarchyError::MethodMismatch(format!(
                "method `{}` needs a {needs} hierarchy, but this one is {}-grouped (build one with `tincull build \
                 --grouping {build}`, or use method `{}`)",
                self.name(),
                grouping.name(),
                if grouping.is_quadtree() { "stewart" } else { "thesis" },
            )))
        };
        match (self, grouping) {
            (CullMethod::Thesis, Grouping::Quadtree { .. }) => wrong("crystal", "crystal"),
            (CullMethod::Stewart, Grouping::Crystal) => wrong("quadtree", "quadtree"),
            _ => Ok(()),
        }
    }

    /// The region method meant for `h`'s grouping: [`CullMethod::Stewart`] for a quadtree, else
    /// [`CullMethod::Thesis`].
    pub fn regions_for(h: &Hierarchy) -> CullMethod {
        if h.build.grouping.is_quadtree() {
            CullMethod::Stewart
        } else {
            CullMethod::Thesis
        }
    }

    /// The method called `name`, if any.
    pub fn from_name(name: &str) -> Option<CullMethod> {
        CullMethod::ALL.into_iter().find(|m| m.name() == name)
    }
}

impl std::fmt::Display for CullMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A culler of any [`CullMethod`].
///
/// Every culler is `Send + Sync` and culls through `&self`: one culler may serve several threads at once, each with
/// its own [`DrawList`].
#[derive(Clone, Debug)]
pub enum AnyCuller {
    /// The safe culler.
    Safe(SafeCuller),
    /// The thesis' region culler.
    Thesis(Culler),
    /// The region culler over a quadtree (Stewart's method).
    Stewart(Culler),
    /// Lloyd & Egbert's horizon culler.
    LloydEgbert(LloydEgbertCuller),
}

impl AnyCuller {
    /// Prepares `method` over `h` (the safe culler with [`SafeParams::default`]), whatever the grouping; see
    /// [`AnyCuller::checked`] for the checks of [`Hierarchy::check_invariants`] and [`CullMethod::check`].
    ///
    /// # Panics
    ///
    /// As the cullers' own constructors, for a hierarchy that breaks [`Hierarchy::check_invariants`] (every loaded
    /// file keeps them; one built or changed in code may not).
    pub fn new(h: &Hierarchy, method: CullMethod) -> AnyCuller {
        AnyCuller::with_params(h, method, SafeParams::default())
    }

    /// Prepares `method` over `h`; `safe` are the safe culler's parameters (`lloyd-egbert` takes its horizon columns
    /// per face from them; the other methods have none). Panics as [`AnyCuller::new`] does.
    pub fn with_params(h: &Hierarchy, method: CullMethod, safe: SafeParams) -> AnyCuller {
        match method {
            CullMethod::Safe => AnyCuller::Safe(SafeCuller::new(h, safe)),
            CullMethod::Thesis => AnyCuller::Thesis(Culler::new(h)),
            CullMethod::Stewart => AnyCuller::Stewart(Culler::new(h)),
            CullMethod::LloydEgbert => AnyCuller::LloydEgbert(LloydEgbertCuller::new(h, safe.columns_per_face)),
        }
    }

    /// Prepares `method` over `h` after [`Hierarchy::check_invariants`] (for a hierarchy built or changed in code;
    /// a loaded file has passed it) and [`CullMethod::check`].
    pub fn checked(h: &Hierarchy, method: CullMethod) -> Result<AnyCuller, HierarchyError> {
        h.check_invariants()?;
        method.check(h)?;
        Ok(AnyCuller::new(h, method))
    }

    /// The method of this culler.
    pub fn method(&self) -> CullMethod {
        match self {
            AnyCuller::Safe(_) => CullMethod::Safe,
            AnyCuller::Thesis(_) => CullMethod::Thesis,
            AnyCuller::Stewart(_) => CullMethod::Stewart,
            AnyCuller::LloydEgbert(_) => CullMethod::LloydEgbert,
        }
    }

    /// Culls for `camera` into `out` (cleared first).
    pub fn cull_into(&self, camera: &Camera, out: &mut DrawList) {
        match self {
            AnyCuller::Safe(c) => c.cull_into(camera, out),
            AnyCuller::Thesis(c) | AnyCuller::Stewart(c) => c.cull_into(camera, out),
            AnyCuller::LloydEgbert(c) => c.cull_into(camera, out),
        }
    }

    /// Culls for `camera`, returning a new draw list.
    pub fn cull(&self, camera: &Camera) -> DrawList {
        let mut out = DrawList::default();
        self.cull_into(camera, &mut out);
        out
    }
}
