//! Ground truth for terrain self-occlusion culling on TINs.
//!
//! The definitions are those of the design notes, section "Measuring accuracy":
//!
//! - [`point_visible`]: a point of the terrain is visible from an eye if the segment between them never passes
//!   below the terrain, decided exactly by walking the segment's x,y projection through the TIN ([`walk`]).
//! - [`visible_triangles`] / [`GroundTruth`]: a triangle is visible if any of its sample points is. The samples are
//!   finite, so the result is a **lower bound** of the true visible set `V`.
//! - [`viewpoints()`]: the six seeded viewpoint classes (`ground`, `low`, `high`, `valley`, `ridge`, `sky`).
//! - [`view_metrics`] and [`summarize`]: false culls, occlusion captured and overdraw of a drawn set against the
//!   ground truth, per viewpoint and aggregated.

#![warn(missing_docs)]

pub mod error;
pub mod locate;
pub mod metrics;
pub mod viewpoints;
pub mod visible;
pub mod walk;

pub use error::{Result, TruthError};
pub use locate::{Locator, ground_heights};
pub use metrics::{Stat, Summary, ViewMetrics, summarize, view_metrics};
pub use viewpoints::{ViewpointClass, viewpoints};
pub use visible::{GroundTruth, MAX_LEVELS, MAX_SPLITS, NUDGE, SAMPLE_ANGLE_DEG, in_view, visible_triangles};
pub use walk::{EPS_REL, MarginReach, point_visible};
