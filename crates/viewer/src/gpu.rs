//! The GPU device: headless setup for renders without a window, or the device an eframe window already made.
//!
//! Headless setup follows wgpu's environment conventions (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, `WGPU_POWER_PREF`), so
//! `WGPU_BACKEND=gl` picks OpenGL where Vulkan is the default. Without a hardware GPU, Mesa's llvmpipe (lavapipe for
//! Vulkan) renders on the CPU. Pipeline-statistics queries are requested when the adapter offers them, so tests
//! can count the primitives the GPU really processed.

use crate::error::{Result, ViewerError};

/// Environment variable that makes a missing adapter a test failure instead of a skip.
pub const REQUIRE_GPU_ENV: &str = "TINCULL_REQUIRE_GPU";

/// A device and its queue, with what the adapter is.
#[derive(Clone, Debug)]
pub struct Gpu {
    /// The logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name, backend, driver.
    pub info: wgpu::AdapterInfo,
}

impl Gpu {
    /// Opens the default adapter without a window (honouring `WGPU_BACKEND` and friends) and creates a device,
    /// with pipeline-statistics queries enabled where the adapter supports them.
    pub fn headless() -> Result<Gpu> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::from_env().unwrap_or_default(),
            ..Default::default()
        };
        let adapter = pollster::block_on(instance.request_adapter(&options))
            .map_err(|e| ViewerError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let wanted = wgpu::Features::PIPELINE_STATISTICS_QUERY;
        let desc = wgpu::DeviceDescriptor {
            label: Some("tincull headless"),
            required_features: adapter.features() & wanted,
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&desc)).map_err(|e| ViewerError::Device(e.to_string()))?;
        Ok(Gpu { device, queue, info })
    }

    /// Wraps a device someone else created (the eframe window's).
    pub fn from_parts(device: wgpu::Device, queue: wgpu::Queue, info: wgpu::AdapterInfo) -> Gpu {
        Gpu { device, queue, info }
    }

    /// `"name (backend)"`, e.g. `"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)"`.
    pub fn describe(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// Whether pipeline-statistics queries are enabled on this device.
    pub fn has_pipeline_statistics(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY)
    }

    /// Waits until the GPU has finished all submitted work.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| ViewerError::Gpu(e.to_string()))
    }
}

/// Whether the environment demands a GPU (`TINCULL_REQUIRE_GPU` set to anything but empty or `0`): then tests must
/// fail rather than skip when no adapter is found.
pub fn gpu_required() -> bool {
    std::env::var(REQUIRE_GPU_ENV).is_ok_and(|v| !v.is_empty() && v != "0")
}
