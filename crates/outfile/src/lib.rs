//! The one writer of every tincull output file (`.tch`, OBJ, MTL, JSON, CSV, PNG).
//!
//! Rules, in the order they are applied:
//!
//! 1. **Check before the work.** [`check`] (and [`Batch::check`]) resolve and validate a path without writing it, so
//!    a command can refuse a bad `-o` before a long build instead of after it: the directory must exist and be a
//!    directory, the target must not be a directory, and the directory must accept a new file (a temporary file
//!    is created and removed there, which is the only reliable test; permission bits lie for root and on
//!    read-only mounts).
//! 2. **Symlinks are followed.** `-o link.tch` writes the file the link points to (an existing target as the
//!    kernel resolves it, so `/dev/stdout -> /proc/self/fd/1 -> pipe:[..]` is seen as the pipe it is; a dangling
//!    link link by link, relative to each link's directory, at most 40 links); the link itself stays a link and the
//!    target is replaced atomically in its own directory. A dangling link creates its target.
//! 3. **Only regular files are replaced.** A directory, FIFO, socket, character or block device (`/dev/full`,
//!    `/dev/null`, a terminal) is refused with an error that names it; nothing is written. The one exception is
//!    the path `-`, which means standard output, written directly (not atomically) where a command allows it
//!    ([`Target::Stdout`]).
//! 4. **Atomic replacement.** The content goes to a fresh temporary file in the target's directory (the `tempfile`
//!    crate: unpredictable name, created exclusively, removed on failure), is flushed to disk, gets the permissions
//!    of the file it replaces (or `0666` less the umask for a new file), and is renamed over the target. A reader
//!    sees the old file or the complete new one, never a half-written one.
//! 5. **All or nothing.** A [`Batch`] writes several files (OBJ + MTL, `.tch` + exports): every content is written
//!    to its temporary file first, and only when all succeeded are they renamed, in order. If a rename fails, the
//!    files this batch had newly created are removed again; files it replaced cannot be restored (their old content
//!    is gone), so a batch's targets should be checked first, which makes that case a race with another process.
//!    Two targets of one batch that resolve to the same file are refused.
//! 6. **Interrupted, nothing left behind.** Every temporary file is registered while it exists;
//!    [`remove_temporaries`] removes them all, for a command's interrupt handler (Ctrl-C, `SIGTERM`) to call before it
//!    exits (a process killed outright, `SIGKILL`, cannot clean up: its `.tincull-*.tmp` files stay). A folder
//!    created for the outputs with [`NewDir`] is removed with them when it is then empty.
//! 7. **Inputs are never outputs.** The files a command reads, declared with [`Batch::input`], cannot be its
//!    outputs: a target that is the same file as an input (the same path once links are followed, or, on Unix, the
//!    same device and inode, which also catches hard links) is refused before anything is written, whichever of the
//!    two was declared first.
#![warn(missing_docs)]

use std::fmt;
use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use tempfile::{NamedTempFile, TempPath};

/// The temporary files that exist now (written, or waiting to be renamed): see [`remove_temporaries`].
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The directories that commands created for their outputs and may still remove: see [`NewDir`].
static NEW_DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn new_dirs() -> MutexGuard<'static, Vec<PathBuf>> {
    NEW_DIRS.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Removes every temporary file this process is writing or has not renamed yet (rule 6), then every directory
/// created with [`NewDir`] and not yet kept that is empty, and keeps the registries locked until the process ends,
/// so that no new one is started: for an interrupt handler, which then exits.
pub fn remove_temporaries() {
    let paths = live();
    for p in paths.iter() {
        let _ = fs::remove_file(p);
    }
    std::mem::forget(paths);
    let dirs = new_dirs();
    for d in dirs.iter().rev() {
        let _ = fs::remove_dir(d);
    }
    std::mem::forget(dirs);
}

/// A directory created for a command's outputs (a tiling plan's folder of tile files): removed again, when empty,
/// if the command fails (this is dropped without [`NewDir::keep`]) or is interrupted ([`remove_temporaries`]), so a
/// failed command leaves no empty folder behind either.
pub struct NewDir {
    path: PathBuf,
    keep: bool,
}

impl NewDir {
    /// Creates the directory `path` (its parent must exist); `None` when a directory is there already (it is then
    /// never removed).
    pub fn create(path: &Path) -> io::Result<Option<NewDir>> {
        let mut dirs = new_dirs();
        match fs::create_dir(path) {
            Ok(()) => {
                dirs.push(path.to_path_buf());
                Ok(Some(NewDir {
                    path: path.to_path_buf(),
                    keep: false,
                }))
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && path.is_dir() => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// Keeps the directory: the command succeeded.
    pub fn keep(mut self) {
        self.keep = true;
    }

    /// Creates the directory `path` and every missing one above it, each a [`NewDir`] (removed again, the deepest
    /// first, unless kept). An error naming the first existing path above `path` when it is not a directory.
    pub fn create_all(path: &Path) -> io::Result<NewDirs> {
        let mut missing = Vec::new();
        let mut at = path;
        while !at.as_os_str().is_empty() && !at.exists() {
            missing.push(at);
            match at.parent() {
                Some(parent) => at = parent,
                None => break,
            }
        }
        if !at.as_os_str().is_empty() && at.exists() && !at.is_dir() {
            return Err(io::Error::new(
                io::ErrorKind::NotADirectory,
                format!("{} is not a directory", at.display()),
            ));
        }
        let mut dirs = NewDirs(Vec::new());
        for dir in missing.into_iter().rev() {
            if let Some(new) = NewDir::create(dir)? {
                dirs.0.push(new);
            }
        }
        Ok(dirs)
    }
}

/// The directories [`NewDir::create_all`] created, outermost first: removed again, the deepest first, when dropped
/// without [`NewDirs::keep`] (each only if empty).
pub struct NewDirs(Vec<NewDir>);

impl NewDirs {
    /// Keeps every directory: the command succeeded.
    pub fn keep(mut self) {
        for dir in self.0.drain(..) {
            dir.keep();
        }
    }
}

impl Drop for NewDirs {
    fn drop(&mut self) {
        while let Some(dir) = self.0.pop() {
            drop(dir);
        }
    }
}

impl Drop for NewDir {
    fn drop(&mut self) {
        let mut dirs = new_dirs();
        if let Some(i) = dirs.iter().position(|p| *p == self.path) {
            dirs.swap_remove(i);
        }
        if !self.keep {
            let _ = fs::remove_dir(&self.path);
        }
    }
}

/// A registered temporary file: listed while this lives.
struct Registered(PathBuf);

impl Registered {
    /// Creates a temporary file with `create` and registers it, holding the registry meanwhile: an interrupt
    /// handler ([`remove_temporaries`]) sees either no file or the registered one.
    fn create(create: impl FnOnce() -> io::Result<NamedTempFile>) -> io::Result<(NamedTempFile, Registered)> {
        let mut paths = live();
        let temp = create()?;
        paths.push(temp.path().to_path_buf());
        let path = temp.path().to_path_buf();
        Ok((temp, Registered(path)))
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        let mut paths = live();
        if let Some(i) = paths.iter().position(|p| *p == self.0) {
            paths.swap_remove(i);
        }
    }
}

/// What went wrong with an output, naming the path the user gave.
#[derive(Debug)]
pub struct Error {
    /// The output path as given.
    pub path: PathBuf,
    /// What is wrong with it.
    pub kind: ErrorKind,
}

/// The kinds of [`Error`].
#[derive(Debug)]
pub enum ErrorKind {
    /// The target is not a regular file (what it is instead).
    NotRegular(&'static str),
    /// The directory of the target does not exist or is not a directory.
    NoDirectory(PathBuf),
    /// The path has no file name (`..`, `/`, empty).
    NoFileName,
    /// The path ends in a separator (`out/`), which names a directory whether or not one exists.
    DirectoryName,
    /// A symlink chain too long or circular.
    SymlinkLoop,
    /// Standard output is not allowed here (a multi-file output or a command that prints to it).
    StdoutNotAllowed,
    /// Two outputs of one command are the same file.
    SameFile(PathBuf),
    /// The output is the same file as one of the command's inputs (the input as given).
    IsInput(PathBuf),
    /// An I/O error (creating, writing, syncing or renaming).
    Io(io::Error),
    /// An I/O error on the temporary file in the target's directory: what was being done (`create`, `write`,
    /// `rename`), the directory, the error.
    InDirectory(&'static str, PathBuf, io::Error),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.path.display();
        match &self.kind {
            ErrorKind::NotRegular(what) => write!(
                f,
                "{p}: is {what}, not a regular file; tincull only replaces regular files: give a file name"
            ),
            ErrorKind::NoDirectory(d) => write!(f, "{p}: the directory {} does not exist", d.display()),
            ErrorKind::NoFileName => write!(f, "{p}: not a file name"),
            ErrorKind::DirectoryName => write!(
                f,
                "{p}: ends in `{}`, which names a directory, not a file; give a file name",
                std::path::MAIN_SEPARATOR
            ),
            ErrorKind::SymlinkLoop => write!(f, "{p}: too many levels of symbolic links"),
            ErrorKind::StdoutNotAllowed => write!(
                f,
                "{p}: this output cannot go to standard output (`-` is taken only where a command's help says so); \
                 give a file name"
            ),
            ErrorKind::SameFile(other) => {
                write!(
                    f,
                    "{p}: the same file as the output {}; give distinct outputs",
                    other.display()
                )
            }
            ErrorKind::IsInput(input) => write!(
                f,
                "{p}: the same file as the input {}; writing it would destroy the input, give another output",
                input.display()
            ),
            ErrorKind::Io(e) => write!(f, "{p}: {e}"),
            ErrorKind::InDirectory(what, dir, e) => {
                write!(
                    f,
                    "{p}: cannot {what} a file in the directory {}: {}",
                    dir.display(),
                    without_temp_path(e)
                )
            }
        }
    }
}

/// No source: the message already ends with the I/O error's own (a source too would print it twice in a chain).
/// [`Error::io_kind`] gives its kind.
impl std::error::Error for Error {}

impl Error {
    /// The kind of the I/O error behind this one (a reader of standard output that went away: `BrokenPipe`).
    pub fn io_kind(&self) -> Option<io::ErrorKind> {
        match &self.kind {
            ErrorKind::Io(e) | ErrorKind::InDirectory(_, _, e) => Some(e.kind()),
            _ => None,
        }
    }
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// The message of an error of `tempfile`, without the name of the temporary file that it appends (` at path
/// "dir/.tmpXXXX"`): a name the user never gave, of a file that no longer exists.
fn without_temp_path(e: &io::Error) -> String {
    let message = e.to_string();
    match message.rfind(" at path \"") {
        Some(i) => message[..i].to_string(),
        None => message,
    }
}

/// An error on the temporary file of `given` in `dir`, while doing `what`.
fn in_dir(given: &Path, what: &'static str, dir: &Path, e: io::Error) -> Error {
    err(given, ErrorKind::InDirectory(what, dir.to_path_buf(), e))
}

fn err(path: &Path, kind: ErrorKind) -> Error {
    Error {
        path: path.to_path_buf(),
        kind,
    }
}

/// A checked output: standard output, or the regular file (existing or not) that a path resolves to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// The path `-`.
    Stdout,
    /// A file.
    File {
        /// The path as given (for messages).
        given: PathBuf,
        /// The file written: symlinks resolved.
        resolved: PathBuf,
        /// Whether it exists now (its permissions are kept).
        exists: bool,
    },
}

impl Target {
    /// The path as given (`-` for standard output).
    pub fn given(&self) -> &Path {
        match self {
            Target::Stdout => Path::new("-"),
            Target::File { given, .. } => given,
        }
    }
}

/// What a file type is, for messages; `None` for a regular file.
fn non_regular(meta: &fs::Metadata) -> Option<&'static str> {
    infile::non_regular(&meta.file_type())
}

/// The directory of `path` (`.` for a bare name).
fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Follows symlinks from `path` to the final non-link path (which may not exist).
fn resolve(given: &Path) -> Result<PathBuf> {
    let mut path = given.to_path_buf();
    for _ in 0..40 {
        match fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = fs::read_link(&path).map_err(|e| err(given, ErrorKind::Io(e)))?;
                path = if link.is_absolute() {
                    link
                } else {
                    dir_of(&path).join(link)
                };
            }
            Ok(_) => return Ok(path),
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(path),
            Err(e) => return Err(err(given, ErrorKind::Io(e))),
        }
    }
    Err(err(given, ErrorKind::SymlinkLoop))
}

/// Checks that `path` can be written (rules 1 to 3 of the crate docs) without writing it; `-` is standard output.
pub fn check(path: &Path) -> Result<Target> {
    if path == Path::new("-") {
        return Ok(Target::Stdout);
    }
    if path.file_name().is_none() {
        return Err(err(path, ErrorKind::NoFileName));
    }
    // `out/` or `x.json/`: the system would answer "Not a directory" or "Is a directory", or take a missing name
    // for a directory to come; the user meant a directory either way.
    if path
        .as_os_str()
        .as_encoded_bytes()
        .last()
        .is_some_and(|&b| std::path::is_separator(char::from(b)))
    {
        return Err(err(path, ErrorKind::DirectoryName));
    }
    // An existing target is judged by what the kernel follows to (this also covers links such as /dev/stdout ->
    // /proc/self/fd/1 -> pipe:[..], which no path resolution can follow); a missing one by resolving the link chain.
    let (resolved, exists) = match fs::metadata(path) {
        Ok(m) => {
            if let Some(what) = non_regular(&m) {
                return Err(err(path, ErrorKind::NotRegular(what)));
            }
            (fs::canonicalize(path).map_err(|e| err(path, ErrorKind::Io(e)))?, true)
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => (resolve(path)?, false),
        // A link chain that cannot be followed (a loop): say so.
        Err(e) => match resolve(path) {
            Err(loop_error) => return Err(loop_error),
            Ok(_) => return Err(err(path, ErrorKind::Io(e))),
        },
    };
    if resolved.file_name().is_none() {
        return Err(err(path, ErrorKind::NoFileName));
    }
    let dir = dir_of(&resolved);
    match fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        _ => return Err(err(path, ErrorKind::NoDirectory(dir.to_path_buf()))),
    }
    // The only reliable test of writability: create (and drop, which removes) a temporary file there.
    NamedTempFile::new_in(dir).map_err(|e| in_dir(path, "create", dir, e))?;
    Ok(Target::File {
        given: path.to_path_buf(),
        resolved,
        exists,
    })
}

/// Checks that `path` can be written and is not standard output (for outputs that must be files).
pub fn check_file(path: &Path) -> Result<Target> {
    match check(path)? {
        Target::Stdout => Err(err(path, ErrorKind::StdoutNotAllowed)),
        t => Ok(t),
    }
}

/// A content written to its temporary file, waiting to be renamed over its target.
struct Staged {
    target: Target,
    /// Written, synced and closed: a batch of thousands of files holds no file descriptor per file.
    temp: Option<TempPath>,
    /// Listed for [`remove_temporaries`] until renamed or dropped (declared after `temp`: dropped after it).
    _registered: Option<Registered>,
}

/// Writes the content of `target` to a temporary file beside it (or to standard output), with the permissions of
/// the file it will replace.
fn stage(target: Target, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<Staged> {
    match &target {
        Target::Stdout => {
            let stdout = io::stdout();
            let mut w = BufWriter::new(stdout.lock());
            write(&mut w)
                .and_then(|_| w.flush())
                .map_err(|e| err(Path::new("-"), ErrorKind::Io(e)))?;
            Ok(Staged {
                target,
                temp: None,
                _registered: None,
            })
        }
        Target::File { given, resolved, .. } => {
            let dir = dir_of(resolved);
            let io = |e| in_dir(given, "write", dir, e);
            let mut builder = tempfile::Builder::new();
            builder.prefix(".tincull-").suffix(".tmp");
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                // A new file gets the usual 0666 less the umask (the mode given to open() is masked).
                builder.permissions(fs::Permissions::from_mode(0o666));
            }
            let (temp, registered) =
                Registered::create(|| builder.tempfile_in(dir)).map_err(|e| in_dir(given, "create", dir, e))?;
            // Keep the permissions of the file being replaced, exactly (set after creation: no umask).
            if let Ok(m) = fs::metadata(resolved)
                && m.is_file()
            {
                fs::set_permissions(temp.path(), m.permissions()).map_err(io)?;
            }
            let mut w = BufWriter::new(temp);
            write(&mut w).map_err(io)?;
            let temp = w.into_inner().map_err(|e| io(e.into_error()))?;
            temp.as_file().sync_all().map_err(io)?;
            Ok(Staged {
                target,
                temp: Some(temp.into_temp_path()),
                _registered: Some(registered),
            })
        }
    }
}

impl Staged {
    /// Renames the temporary file over the target (after re-checking that the target is still a regular file or
    /// absent).
    fn commit(self) -> Result<()> {
        let (Target::File { given, resolved, .. }, Some(temp), _registered) =
            (self.target, self.temp, self._registered)
        else {
            return Ok(());
        };
        if let Ok(m) = fs::metadata(&resolved)
            && let Some(what) = non_regular(&m)
        {
            return Err(err(&given, ErrorKind::NotRegular(what)));
        }
        temp.persist(&resolved)
            .map_err(|e| in_dir(&given, "rename", dir_of(&resolved), e.error))?;
        Ok(())
    }
}

/// Writes one output: checks `path` (rules 1 to 3), then writes it through `write` atomically (rule 4); `-` writes
/// to standard output.
pub fn write(path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
    stage(check(path)?, write)?.commit()
}

/// Writes `bytes` to `path` as [`write()`] does.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write(path, |w| w.write_all(bytes))
}

/// Several outputs of one command, all or nothing (rule 5 of the crate docs). Check every target first
/// ([`Batch::check`], before the work), then [`Batch::add`] each content, then [`Batch::commit`].
#[derive(Default)]
pub struct Batch {
    targets: Vec<Target>,
    staged: Vec<Staged>,
    /// Files the command reads: `(path as given, its identity)`.
    inputs: Vec<(PathBuf, FileId)>,
}

impl Batch {
    /// An empty batch.
    pub fn new() -> Batch {
        Batch::default()
    }

    /// Declares `path` an input of the command (rule 7): no output of this batch may be the same file. An input
    /// that does not exist is nothing to protect (reading it will fail); `-` (standard input) is ignored. Refused
    /// when an output checked before is that file.
    pub fn input(&mut self, path: &Path) -> Result<()> {
        if path == Path::new("-") {
            return Ok(());
        }
        let Some(id) = FileId::of_existing(path) else {
            return Ok(());
        };
        for t in self.targets.iter().chain(self.staged.iter().map(|s| &s.target)) {
            if let Target::File { given, resolved, .. } = t
                && FileId::of_target(resolved) == id
            {
                return Err(err(given, ErrorKind::IsInput(path.to_path_buf())));
            }
        }
        self.inputs.push((path.to_path_buf(), id));
        Ok(())
    }

    /// Checks `path` as an output of this batch: writable, a file (standard output cannot take part in a batch),
    /// not the same file as an output checked before, nor as an input ([`Batch::input`]).
    pub fn check(&mut self, path: &Path) -> Result<()> {
        let target = check_file(path)?;
        let Target::File { resolved, .. } = &target else {
            return Err(err(path, ErrorKind::StdoutNotAllowed));
        };
        let canon = canonical(resolved);
        for t in &self.targets {
            if let Target::File { given, resolved: r, .. } = t
                && canonical(r) == canon
            {
                return Err(err(path, ErrorKind::SameFile(given.clone())));
            }
        }
        let id = FileId::of_target(resolved);
        if let Some((input, _)) = self.inputs.iter().find(|(_, i)| *i == id) {
            return Err(err(path, ErrorKind::IsInput(input.clone())));
        }
        self.targets.push(target);
        Ok(())
    }

    /// Writes the content of `path` (checked now if it was not) to its temporary file.
    pub fn add(&mut self, path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
        if !self.targets.iter().any(|t| t.given() == path) {
            self.check(path)?;
        }
        let Some(i) = self.targets.iter().position(|t| t.given() == path) else {
            return Err(err(path, ErrorKind::NoFileName));
        };
        let target = self.targets.remove(i);
        self.staged.push(stage(target, write)?);
        Ok(())
    }

    /// Renames every staged file over its target, in the order added. On failure, the files this batch newly
    /// created are removed again, and the temporary files of the rest are dropped.
    pub fn commit(self) -> Result<()> {
        let mut created: Vec<PathBuf> = Vec::new();
        for s in self.staged {
            let new = match &s.target {
                Target::File { resolved, exists, .. } => (!exists).then(|| resolved.clone()),
                Target::Stdout => None,
            };
            if let Err(e) = s.commit() {
                for p in &created {
                    let _ = fs::remove_file(p);
                }
                return Err(e);
            }
            created.extend(new);
        }
        Ok(())
    }
}

/// What makes two paths the same file: on Unix the device and inode of an existing file (so hard links match too),
/// else (and for a file that does not exist yet) the canonical path.
#[derive(Clone, Debug, PartialEq, Eq)]
enum FileId {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

impl FileId {
    /// The identity of an existing file, following links; `None` when it cannot be read.
    #[cfg(unix)]
    fn of_existing(path: &Path) -> Option<FileId> {
        use std::os::unix::fs::MetadataExt;
        let meta = fs::metadata(path).ok()?;
        Some(FileId::Inode(meta.dev(), meta.ino()))
    }

    /// The identity of an existing file, following links; `None` when it cannot be read.
    #[cfg(not(unix))]
    fn of_existing(path: &Path) -> Option<FileId> {
        fs::metadata(path).ok()?;
        fs::canonicalize(path).ok().map(FileId::Path)
    }

    /// The identity of an output target (resolved; it may not exist yet).
    fn of_target(resolved: &Path) -> FileId {
        FileId::of_existing(resolved).unwrap_or_else(|| FileId::Path(canonical(resolved)))
    }
}

/// The canonical form of a path whose file may not exist yet (its directory does).
fn canonical(path: &Path) -> PathBuf {
    if let Ok(p) = fs::canonicalize(path) {
        return p;
    }
    match (fs::canonicalize(dir_of(path)), path.file_name()) {
        (Ok(d), Some(n)) => d.join(n),
        _ => path.to_path_buf(),
    }
}
