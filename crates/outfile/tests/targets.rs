//! Every kind of target the writer meets, made in a temporary directory (never real devices): regular files
//! (permissions kept), symlinks (followed, the link stays), dangling links, FIFOs and directories (refused, nothing
//! written), missing and read-only directories (refused before the work), and batches (all or nothing, two names
//! for one file refused).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use outfile::{Batch, ErrorKind, NewDir, Target, check, write, write_bytes};

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().expect("temporary directory")
}

/// Names in `dir` (the writer must leave no temporary files behind).
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo").arg(path).status().expect("run mkfifo");
    assert!(status.success(), "mkfifo {}", path.display());
}

#[test]
fn writes_a_new_file_and_replaces_an_old_one() {
    let dir = tmp();
    let p = dir.path().join("a.txt");
    write_bytes(&p, b"one").expect("new file");
    assert_eq!(fs::read(&p).expect("read"), b"one");
    write_bytes(&p, b"two").expect("replace");
    assert_eq!(fs::read(&p).expect("read"), b"two");
    assert_eq!(names(dir.path()), ["a.txt"]);
}

#[cfg(unix)]
#[test]
fn keeps_the_permissions_of_the_replaced_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmp();
    let p = dir.path().join("a.txt");
    fs::write(&p, "old").expect("write");
    fs::set_permissions(&p, fs::Permissions::from_mode(0o640)).expect("chmod");
    write_bytes(&p, b"new").expect("replace");
    assert_eq!(fs::metadata(&p).expect("stat").permissions().mode() & 0o7777, 0o640);
    // A new file is not private to its owner the way a bare temporary file would be.
    let q = dir.path().join("new.txt");
    write_bytes(&q, b"x").expect("new");
    let mode = fs::metadata(&q).expect("stat").permissions().mode() & 0o777;
    assert_ne!(mode, 0o600, "a new file gets 0666 less the umask, got {mode:o}");
    assert_eq!(mode & 0o600, 0o600);
}

#[test]
fn a_failed_write_keeps_the_old_file_and_leaves_nothing() {
    let dir = tmp();
    let p = dir.path().join("a.txt");
    fs::write(&p, "old").expect("write");
    let e = write(&p, |w| {
        w.write_all(b"partial")?;
        Err(std::io::Error::other("disk full"))
    })
    .expect_err("the write fails");
    assert!(
        e.to_string().contains("a.txt") && e.to_string().contains("disk full"),
        "{e}"
    );
    assert_eq!(fs::read_to_string(&p).expect("read"), "old");
    assert_eq!(names(dir.path()), ["a.txt"]);
}

#[cfg(unix)]
#[test]
fn a_symlink_is_followed_and_stays_a_link() {
    let dir = tmp();
    let target = dir.path().join("real.tch");
    let link = dir.path().join("link.tch");
    fs::write(&target, "old").expect("write");
    std::os::unix::fs::symlink("real.tch", &link).expect("symlink");
    write_bytes(&link, b"new").expect("write through the link");
    assert!(fs::symlink_metadata(&link).expect("lstat").file_type().is_symlink());
    assert_eq!(fs::read(&target).expect("read"), b"new");
    assert_eq!(names(dir.path()), ["link.tch", "real.tch"]);
}

#[cfg(unix)]
#[test]
fn a_link_into_another_directory_writes_there() {
    let dir = tmp();
    fs::create_dir(dir.path().join("sub")).expect("mkdir");
    let link = dir.path().join("link.txt");
    std::os::unix::fs::symlink("sub/file.txt", &link).expect("symlink");
    // Dangling: the target is created.
    write_bytes(&link, b"x").expect("write");
    assert_eq!(fs::read(dir.path().join("sub/file.txt")).expect("read"), b"x");
    assert_eq!(names(&dir.path().join("sub")), ["file.txt"]);
}

#[cfg(unix)]
#[test]
fn a_symlink_loop_is_refused() {
    let dir = tmp();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    std::os::unix::fs::symlink("b", &a).expect("symlink");
    std::os::unix::fs::symlink("a", &b).expect("symlink");
    let e = check(&a).expect_err("a loop");
    assert!(matches!(e.kind, ErrorKind::SymlinkLoop), "{e}");
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_and_left_alone() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tmp();
    let fifo = dir.path().join("pipe");
    mkfifo(&fifo);
    let e = write_bytes(&fifo, b"x").expect_err("a FIFO is not replaced");
    assert!(matches!(e.kind, ErrorKind::NotRegular(_)), "{e}");
    assert!(e.to_string().contains("FIFO") && e.to_string().contains("pipe"), "{e}");
    assert!(fs::symlink_metadata(&fifo).expect("lstat").file_type().is_fifo());
    assert_eq!(names(dir.path()), ["pipe"]);
    // Also through a symlink to it.
    let link = dir.path().join("link");
    std::os::unix::fs::symlink("pipe", &link).expect("symlink");
    assert!(matches!(
        check(&link).expect_err("refused").kind,
        ErrorKind::NotRegular(_)
    ));
}

#[test]
fn a_directory_is_refused() {
    let dir = tmp();
    let sub = dir.path().join("sub");
    fs::create_dir(&sub).expect("mkdir");
    let e = write_bytes(&sub, b"x").expect_err("a directory");
    assert!(matches!(e.kind, ErrorKind::NotRegular("a directory")), "{e}");
    assert!(sub.is_dir());
}

#[test]
fn a_missing_directory_is_refused_before_the_work() {
    let dir = tmp();
    let p = dir.path().join("nodir/x.tch");
    let e = check(&p).expect_err("no directory");
    assert!(matches!(e.kind, ErrorKind::NoDirectory(_)), "{e}");
    assert!(e.to_string().contains("nodir"), "{e}");
    let mut ran = false;
    assert!(
        write(&p, |_| {
            ran = true;
            Ok(())
        })
        .is_err()
    );
    assert!(!ran, "the content is not produced for an output that cannot be written");
}

#[cfg(unix)]
#[test]
fn a_read_only_directory_is_refused_unless_privileged() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmp();
    let ro = dir.path().join("ro");
    fs::create_dir(&ro).expect("mkdir");
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).expect("chmod");
    // Root (as in many containers) may write there anyway: then the writer must succeed too.
    let privileged = fs::write(ro.join("probe"), "x").is_ok();
    let _ = fs::remove_file(ro.join("probe"));
    let p = ro.join("x.txt");
    let result = check(&p);
    if privileged {
        result.expect("writable for this user");
        write_bytes(&p, b"x").expect("written");
    } else {
        let e = result.expect_err("read-only");
        assert!(matches!(e.kind, ErrorKind::InDirectory("create", _, _)), "{e}");
        assert!(
            e.to_string().contains("x.txt") && !e.to_string().contains(".tmp"),
            "{e}"
        );
        assert!(write_bytes(&p, b"x").is_err());
        assert_eq!(names(&ro), Vec::<String>::new());
    }
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).expect("chmod back");
}

/// A directory that takes no new file (here /proc) is named in the error, not the temporary file that could not be
/// created there.
#[cfg(target_os = "linux")]
#[test]
fn a_directory_that_refuses_new_files_is_named() {
    let e = check(Path::new("/proc/tincull-out.json")).expect_err("/proc takes no new file");
    let message = e.to_string();
    assert!(matches!(e.kind, ErrorKind::InDirectory("create", _, _)), "{message}");
    assert!(
        message.starts_with("/proc/tincull-out.json: cannot create a file in the directory /proc: "),
        "{message}"
    );
    assert!(!message.contains(".tmp") && !message.contains("at path"), "{message}");
}

#[test]
fn dash_is_standard_output() {
    assert_eq!(check(Path::new("-")).expect("stdout"), Target::Stdout);
    assert!(outfile::check_file(Path::new("-")).is_err());
}

#[test]
fn a_batch_is_all_or_nothing() {
    let dir = tmp();
    let a = dir.path().join("a.obj");
    let b = dir.path().join("a.mtl");
    fs::write(&a, "old a").expect("write");
    let mut batch = Batch::new();
    batch.check(&a).expect("a");
    batch.check(&b).expect("b");
    batch.add(&b, |w| w.write_all(b"new b")).expect("b staged");
    let e = batch.add(&a, |_| Err(std::io::Error::other("disk full")));
    assert!(e.is_err());
    drop(batch);
    assert_eq!(fs::read_to_string(&a).expect("read"), "old a");
    assert!(!b.exists(), "nothing of a failed batch is written");
    assert_eq!(names(dir.path()), ["a.obj"]);

    let mut batch = Batch::new();
    batch.add(&b, |w| w.write_all(b"new b")).expect("b");
    batch.add(&a, |w| w.write_all(b"new a")).expect("a");
    batch.commit().expect("commit");
    assert_eq!(fs::read_to_string(&a).expect("read"), "new a");
    assert_eq!(fs::read_to_string(&b).expect("read"), "new b");
    assert_eq!(names(dir.path()), ["a.mtl", "a.obj"]);
}

#[cfg(unix)]
#[test]
fn a_batch_commit_that_fails_removes_the_files_it_created() {
    let dir = tmp();
    let a = dir.path().join("new.mtl");
    let b = dir.path().join("later");
    let mut batch = Batch::new();
    batch.add(&a, |w| w.write_all(b"a")).expect("a");
    batch.add(&b, |w| w.write_all(b"b")).expect("b");
    // Between staging and the rename, `later` becomes a FIFO: its rename is refused.
    mkfifo(&b);
    let e = batch.commit().expect_err("refused");
    assert!(matches!(e.kind, ErrorKind::NotRegular(_)), "{e}");
    assert!(!a.exists(), "the batch's new file is removed again");
    assert_eq!(names(dir.path()), ["later"]);
}

#[test]
fn two_names_for_one_file_are_refused() {
    let dir = tmp();
    let a: PathBuf = dir.path().join("same.mtl");
    let b = dir.path().join(".").join("same.mtl");
    let mut batch = Batch::new();
    batch.check(&a).expect("a");
    let e = batch.check(&b).expect_err("the same file");
    assert!(matches!(e.kind, ErrorKind::SameFile(_)), "{e}");
}

#[test]
fn an_input_is_never_an_output() {
    let dir = tmp();
    let input = dir.path().join("terrain.obj");
    fs::write(&input, b"v 0 0 0\n").expect("input");
    let link = dir.path().join("link.obj");
    std::os::unix::fs::symlink(&input, &link).expect("symlink");
    let hard = dir.path().join("hard.obj");
    fs::hard_link(&input, &hard).expect("hard link");
    // Declared first, then the same file by its own name, through a link, through a hard link, by another spelling.
    for output in [
        input.clone(),
        link.clone(),
        hard.clone(),
        dir.path().join(".").join("terrain.obj"),
    ] {
        let mut batch = Batch::new();
        batch.input(&input).expect("input");
        let e = batch.check(&output).expect_err("the input");
        assert!(matches!(e.kind, ErrorKind::IsInput(_)), "{}: {e}", output.display());
        assert!(e.to_string().contains("terrain.obj"), "{e}");
    }
    // Declared after the output.
    let mut batch = Batch::new();
    batch.check(&link).expect("not an input yet");
    let e = batch.input(&input).expect_err("already an output");
    assert!(matches!(e.kind, ErrorKind::IsInput(_)), "{e}");
    // Other files, a missing input and standard input are fine.
    let mut batch = Batch::new();
    batch.input(&input).expect("input");
    batch
        .input(&dir.path().join("missing.obj"))
        .expect("a missing input protects nothing");
    batch.input(Path::new("-")).expect("standard input");
    batch.check(&dir.path().join("out.tch")).expect("another file");
    batch
        .add(&dir.path().join("out.tch"), |w| w.write_all(b"x"))
        .expect("add");
    batch.commit().expect("commit");
    assert_eq!(fs::read(&input).expect("read"), b"v 0 0 0\n");
}

/// `NewDir::create_all` makes every missing folder down to the one asked for; dropped, it removes them all, the
/// deepest first (none is left above an empty one); kept, they stay; a file on the way is named.
#[test]
fn new_dirs_are_removed_deepest_first_unless_kept() {
    let dir = tmp();
    let nested = dir.path().join("a").join("b").join("c");
    let made = NewDir::create_all(&nested).expect("create");
    assert!(nested.is_dir());
    drop(made);
    assert_eq!(names(dir.path()), Vec::<String>::new());

    fs::create_dir(dir.path().join("a")).expect("an existing folder");
    let made = NewDir::create_all(&nested).expect("create");
    drop(made);
    assert_eq!(names(dir.path()), ["a"], "a folder that was there stays");
    assert_eq!(names(&dir.path().join("a")), Vec::<String>::new());

    NewDir::create_all(&nested).expect("create").keep();
    assert!(nested.is_dir());

    fs::write(dir.path().join("f"), b"").expect("a file");
    let e = match NewDir::create_all(&dir.path().join("f").join("g")) {
        Err(e) => e,
        Ok(_) => panic!("a folder made under a file"),
    };
    assert!(e.to_string().contains("f is not a directory"), "{e}");
}
