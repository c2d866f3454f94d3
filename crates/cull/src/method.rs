//! The run-time culling methods behind one interface, chosen by name (`--method` on the command line).

use crate::culler::{Camera, Culler, DrawList};
use crate::hierarchy::Hierarchy;
use crate::safe::{SafeCuller, SafeParams};

/// A run-time culling method over a [`Hierarchy`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CullMethod {
    /// [`SafeCuller`]: front to back against a conservative horizon; never culls a visible triangle (the default).
    #[default]
    Safe,
    /// [`Culler`]: the thesis' test of the camera against each node's precomputed sector regions (not conservative).
    Thesis,
}

impl CullMethod {
    /// Every method, the default first.
    pub const ALL: [CullMethod; 2] = [CullMethod::Safe, CullMethod::Thesis];

    /// The method's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            CullMethod::Safe => "safe",
            CullMethod::Thesis => "thesis",
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
#[derive(Clone, Debug)]
pub enum AnyCuller {
    /// The safe culler.
    Safe(SafeCuller),
    /// The thesis' region culler.
    Thesis(Culler),
}

impl AnyCuller {
    /// Prepares `method` over `h` (the safe culler with [`SafeParams::default`]).
    pub fn new(h: &Hierarchy, method: CullMethod) -> AnyCuller {
        AnyCuller::with_params(h, method, SafeParams::default())
    }

    /// Prepares `method` over `h`; `safe` are the safe culler's parameters (the other methods have none).
    pub fn with_params(h: &Hierarchy, method: CullMethod, safe: SafeParams) -> AnyCuller {
        match method {
            CullMethod::Safe => AnyCuller::Safe(SafeCuller::new(h, safe)),
            CullMethod::Thesis => AnyCuller::Thesis(Culler::new(h)),
        }
    }

    /// The method of this culler.
    pub fn method(&self) -> CullMethod {
        match self {
            AnyCuller::Safe(_) => CullMethod::Safe,
            AnyCuller::Thesis(_) => CullMethod::Thesis,
        }
    }

    /// Culls for `camera` into `out` (cleared first).
    pub fn cull_into(&self, camera: &Camera, out: &mut DrawList) {
        match self {
            AnyCuller::Safe(c) => c.cull_into(camera, out),
            AnyCuller::Thesis(c) => c.cull_into(camera, out),
        }
    }

    /// Culls for `camera`, returning a new draw list.
    pub fn cull(&self, camera: &Camera) -> DrawList {
        let mut out = DrawList::default();
        self.cull_into(camera, &mut out);
        out
    }
}
