//! wgpu rendering of TIN terrains and their occlusion hierarchies.
//!
//! - Headless: [`headless::render`] draws the map, the orbit overview (with a viewpoint's culling) or an eye view
//!   into an image, and can compare culled with unculled frames; [`png_out::write_png`] saves it.
//! - Interactive: [`app::run`] opens an eframe window with a fly/orbit camera, the culler's live statistics, ground
//!   truth on demand and a background rebuild with the `pipeline` crate.
//!
//! Geometry goes to the GPU as f32 relative to the hierarchy's (or TIN's) local origin; each hierarchy range the
//! culler returns is one indexed draw.
#![warn(missing_docs)]

pub mod app;
pub mod camera;
pub mod error;
pub mod gpu;
pub mod headless;
pub mod palette;
pub mod png_out;
pub mod render;
pub mod scene;

pub use error::{Result, ViewerError};
pub use gpu::{Gpu, REQUIRE_GPU_ENV, gpu_required};
pub use headless::{Comparison, RenderOptions, RenderOutput, ViewKind, render, validate};
pub use palette::{ORPHAN_COLOUR, group_colour};
pub use png_out::{read_png, write_png};
pub use render::{DrawItem, DrawStyle, FrameStats, Renderer, RgbaImage};
pub use scene::{ColourMode, GpuScene, Terrain};
