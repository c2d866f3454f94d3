//! The `tincull` command-line tool.

use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    quiet_headless_vulkan();
    remove_temporaries_on_interrupt();
    let cli = tincull::cli::Cli::parse_args();
    match tincull::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of standard output went away (`tincull export h.tch --export-json - | head`): nothing to say,
        // and the status a shell gives a process ended by SIGPIPE.
        Err(e)
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .map(std::io::Error::kind)
                    .or_else(|| c.downcast_ref::<outfile::Error>().and_then(outfile::Error::io_kind))
                    == Some(std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            ExitCode::from(141)
        }
        Err(e) => {
            // A closed stderr cannot take the message; the status still tells.
            let _ = writeln!(std::io::stderr(), "error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Ctrl-C, `SIGTERM` or `SIGHUP` while an output is written: its temporary files are removed (outputs are all or
/// nothing, and nothing else is left behind either), then the process ends by that signal, as it would have without
/// the handler (a shell reports status 130, 143 or 129).
/// Where the shell made the process ignore Ctrl-C (a background job of a script), it keeps ignoring it; `SIGTERM`
/// and `SIGHUP` still clean up.
#[cfg(unix)]
fn remove_temporaries_on_interrupt() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut caught = vec![SIGTERM, SIGHUP];
    if !interrupts_ignored() {
        caught.push(SIGINT);
    }
    // Without a handler (it cannot be installed), a signal still leaves every output untouched; only the hidden
    // temporary files would stay.
    let Ok(mut signals) = signal_hook::iterator::Signals::new(&caught) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            outfile::remove_temporaries();
            // The signal's default action (termination), so that the parent sees which signal ended the process;
            // the status a shell would report, should that fail.
            let _ = signal_hook::low_level::emulate_default_handler(signal);
            std::process::exit(128 + signal);
        }
    });
}

/// Ctrl-C while an output is written: its temporary files are removed, then the process exits with status 130.
#[cfg(not(unix))]
fn remove_temporaries_on_interrupt() {
    let _ = ctrlc::set_handler(|| {
        outfile::remove_temporaries();
        std::process::exit(130);
    });
}

/// Whether `SIGINT` is ignored (inherited from the shell).
#[cfg(unix)]
fn interrupts_ignored() -> bool {
    // SAFETY: with a null new action, sigaction only writes the current one into `old`, a plain C struct for which
    // all zeroes is a valid value.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(libc::SIGINT, std::ptr::null(), &mut old) == 0 && old.sa_sigaction == libc::SIG_IGN
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
