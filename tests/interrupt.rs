//! Ctrl-C (`SIGINT`) while a command works: it ends by that signal (as without a handler: a shell reports 130)
//! and leaves neither its outputs nor temporary files; where the shell made it ignore `SIGINT` (a background job of a script), it keeps ignoring it, and `SIGTERM`
//! and `SIGHUP` still clean up.

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

mod common;

use common::{mesh, ok, s};

/// Runs `tincull args` with `SIGINT` at its default disposition (or ignored), sends it `SIGINT` after `delay`, and
/// returns how it ended: `Ok(status)` when it exited, `Err(signal)` when a signal ended it.
fn interrupted(args: &[&str], delay: Duration, ignore: bool) -> Result<i32, i32> {
    signalled(args, delay, ignore, libc::SIGINT)
}

/// [`interrupted`] with the signal `signal`.
fn signalled(args: &[&str], delay: Duration, ignore: bool, signal: libc::c_int) -> Result<i32, i32> {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_tincull"));
    cmd.args(args).stdout(Stdio::null()).stderr(Stdio::null());
    // SAFETY: only async-signal-safe calls between fork and exec (signal(2)).
    unsafe {
        cmd.pre_exec(move || {
            libc::signal(libc::SIGINT, if ignore { libc::SIG_IGN } else { libc::SIG_DFL });
            Ok(())
        });
    }
    let mut child = cmd.spawn().expect("the binary runs");
    std::thread::sleep(delay);
    // SAFETY: kill(2) on the child's pid.
    unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    let status = child.wait().expect("wait");
    status
        .code()
        .ok_or_else(|| status.signal().expect("an exit status or a signal"))
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn an_interrupted_command_leaves_nothing_behind() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tch = dir.path().join("h.tch");
    ok(&["build", "-q", s(&mesh("jacksboro-10k.obj")), "-o", s(&tch)]);
    let csv = dir.path().join("e.csv");
    let json = dir.path().join("e.json");
    // `eval` works for seconds before it writes: interrupted at several moments, nothing is left.
    for ms in [150, 400, 900] {
        let code = interrupted(
            &[
                "eval",
                s(&tch),
                "--viewpoints",
                "50",
                "--csv",
                s(&csv),
                "--export-json",
                s(&json),
            ],
            Duration::from_millis(ms),
            false,
        );
        assert_eq!(code, Err(libc::SIGINT), "interrupted after {ms} ms");
        assert_eq!(names(dir.path()), ["h.tch"], "after {ms} ms");
    }
    // Ignored by the shell, the interrupt changes nothing: the command finishes.
    let code = interrupted(
        &[
            "eval",
            s(&tch),
            "--viewpoints",
            "1",
            "--classes",
            "ground",
            "--csv",
            s(&csv),
        ],
        Duration::from_millis(100),
        true,
    );
    assert_eq!(code, Ok(0));
    assert_eq!(names(dir.path()), ["e.csv", "h.tch"]);
    std::fs::remove_file(&csv).expect("remove");
    // There, `SIGTERM` and `SIGHUP` still clean up (they killed the process outright, leaving its temporary files).
    for signal in [libc::SIGTERM, libc::SIGHUP] {
        let code = signalled(
            &["eval", s(&tch), "--viewpoints", "50", "--csv", s(&csv)],
            Duration::from_millis(400),
            true,
            signal,
        );
        assert_eq!(code, Err(signal), "signal {signal}");
        assert_eq!(names(dir.path()), ["h.tch"], "signal {signal}");
    }
}

/// `tiles plan` creates the folder of its tiles' files: interrupted while it writes them, it removes the folder too.
#[test]
fn an_interrupted_plan_leaves_no_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let npy = dir.path().join("g.npy");
    ok(&["synth", "--vertices", "250000", "--rng-seed", "1", "-o", s(&npy), "-q"]);
    let before = names(dir.path());
    let plan = dir.path().join("plan.json");
    // Some 15,000 tiles: seconds of far-field files.
    for ms in [400, 1200] {
        let code = interrupted(
            &["tiles", "plan", s(&npy), "-o", s(&plan), "--tile", "4", "-q"],
            Duration::from_millis(ms),
            false,
        );
        assert_eq!(code, Err(libc::SIGINT), "interrupted after {ms} ms");
        assert_eq!(names(dir.path()), before, "after {ms} ms");
    }
}

/// `demo` creates its output folder: interrupted while it builds and evaluates, it removes the folder again (it once
/// left it behind, empty).
#[test]
fn an_interrupted_demo_leaves_no_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let code = interrupted(
        &[
            "demo",
            s(&mesh("jacksboro-10k.obj")),
            "--out-dir",
            s(&out),
            "--viewpoints",
            "20",
        ],
        Duration::from_millis(1500),
        false,
    );
    assert_eq!(code, Err(libc::SIGINT));
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
}
