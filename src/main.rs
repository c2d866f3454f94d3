//! The `tincull` command-line tool.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    quiet_headless_vulkan();
    let cli = tincull::cli::Cli::parse();
    match tincull::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Mesa's Vulkan device-select layer asks a Wayland compositor which GPU is the default. Without a session
/// (`XDG_RUNTIME_DIR` unset: a headless machine, CI, a container) libwayland then prints "error: XDG_RUNTIME_DIR is
/// invalid or not set in the environment." twice on every render, which reads like an error of ours. With no display
/// there is no default GPU to ask for, so the layer is switched off (`NODEVICE_SELECT=1`) unless the user set that
/// variable; wgpu still picks the adapter by power preference (`WGPU_POWER_PREF`).
fn quiet_headless_vulkan() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() && std::env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: the first statement of `main`, before any thread is started: nothing reads or writes the
        // environment concurrently.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}
