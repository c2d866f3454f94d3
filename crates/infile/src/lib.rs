//! The one opener of every tincull input file (meshes, DEMs, `.tch`, `.pvs`, tile plans, eye lists, configs), and
//! the one description of a file type in messages ([`non_regular`]).
//!
//! A path given as an input is read whole, so what it names must end: a regular file, a pipe (`<(gen)`,
//! `/dev/stdin` fed by a pipe or a file) or a terminal (typed input, to Ctrl-D). Any other character or block device
//! (`/dev/zero`, `/dev/urandom`, a disk), a socket or a directory is refused with an error of kind
//! [`std::io::ErrorKind::InvalidInput`] that says what it is: read whole, `/dev/zero` would grow a buffer until the
//! machine runs out of memory. The kind is taken from the opened file itself (`fstat`), not from the path, so a link or
//! a rename between the check and the read changes nothing. The callers name the path in their own errors.
//!
//! A pipe or a terminal gives its bytes once, yet a command may look at an input's first bytes (to tell a hierarchy
//! from a mesh) before its reader reads it, and look again to word an error. So in a process that asked for it with
//! [`keep_pipes`] (a one-shot program: the `tincull` command line), the first [`read`] or [`peek`] of a pipe or a
//! terminal reads it whole and keeps its bytes, and every later [`read`] or [`peek`] of the same path in this process
//! is answered from them: the pipe reads as a file would. A long-lived program (a renderer loading hierarchies through
//! the library or its C API) does not ask: every read of a pipe then reads the pipe afresh, as the same path may
//! name another pipe, or a file, later. A regular file is read from disk each time. [`open`] streams a file; it
//! refuses a path whose bytes are kept (its readers need a regular file they can seek).

#![warn(missing_docs)]

use std::fs::{File, FileType};
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The bytes of the pipes and terminals read so far, by the path they were read by.
static KEPT: Mutex<Vec<(PathBuf, Arc<[u8]>)>> = Mutex::new(Vec::new());

/// Whether this process keeps the bytes of the pipes and terminals it reads ([`keep_pipes`]).
static KEEPING: AtomicBool = AtomicBool::new(false);

/// Makes this process keep the bytes of every pipe and terminal it reads from now on, so that later reads and looks
/// of the same path get them again (see the crate documentation). For one-shot programs only: the bytes are kept
/// until the process ends, and a path is never read again.
pub fn keep_pipes() {
    KEEPING.store(true, Ordering::SeqCst);
}

/// The kept bytes of `path`, if it is a pipe or terminal read before.
fn kept(path: &Path) -> Option<Arc<[u8]>> {
    if !KEEPING.load(Ordering::SeqCst) {
        return None;
    }
    let kept = KEPT.lock().unwrap_or_else(|e| e.into_inner());
    kept.iter().find(|(p, _)| p == path).map(|(_, b)| Arc::clone(b))
}

/// Reads the rest of `file`, opened from `path`; the bytes of a pipe or a terminal are kept for the next reads.
fn whole(mut file: File, path: &Path) -> io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes)?;
    if KEEPING.load(Ordering::SeqCst) && !file.metadata()?.is_file() {
        KEPT.lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((path.to_path_buf(), bytes.as_slice().into()));
    }
    Ok(bytes)
}

/// Opens `path` for reading, refusing what is not a regular file, a pipe or a terminal, and a pipe or terminal whose
/// bytes were read already (see the crate documentation).
pub fn open(path: &Path) -> io::Result<File> {
    use std::io::IsTerminal;
    if kept(path).is_some() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "a pipe or terminal, read already (it gives its bytes once): this input is read from a regular file",
        ));
    }
    let file = File::open(path).map_err(|e| match e.kind() {
        // Outputs take `-` for standard output; an input takes the device's name.
        io::ErrorKind::NotFound if path == Path::new("-") => io::Error::new(
            io::ErrorKind::NotFound,
            "no file of that name (standard input is read as /dev/stdin)",
        ),
        _ => e,
    })?;
    match refused(&file.metadata()?.file_type()) {
        None => Ok(file),
        Some(_) if file.is_terminal() => Ok(file),
        Some(what) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{what}, not a file"),
        )),
    }
}

/// Reads the whole of `path` ([`open`]'s rules; a pipe or a terminal as when it was first read).
pub fn read(path: &Path) -> io::Result<Vec<u8>> {
    match kept(path) {
        Some(bytes) => Ok(bytes.to_vec()),
        None => whole(open(path)?, path),
    }
}

/// Reads the whole of `path` ([`read`]) when its first `n` bytes pass `wanted`, and else only those bytes (all of
/// them when the file is shorter): a reader that checks a magic number does not read a file of another kind whole to
/// refuse it. A pipe or a terminal is read whole all the same in a process that keeps pipes ([`keep_pipes`]), whose
/// later reads want its bytes; otherwise the rest of a refused pipe is left unread.
pub fn read_if(path: &Path, n: usize, wanted: impl FnOnce(&[u8]) -> bool) -> io::Result<Vec<u8>> {
    if let Some(bytes) = kept(path) {
        return Ok(bytes.to_vec());
    }
    let mut file = open(path)?;
    if KEEPING.load(Ordering::SeqCst) && !file.metadata()?.is_file() {
        return whole(file, path);
    }
    let mut bytes = Vec::new();
    (&mut file).take(n as u64).read_to_end(&mut bytes)?;
    if wanted(&bytes) {
        file.read_to_end(&mut bytes)?;
    }
    Ok(bytes)
}

/// Reads the whole of `path` as UTF-8 text ([`read`]; text that is not UTF-8 is an [`io::ErrorKind::InvalidData`]
/// error).
pub fn read_to_string(path: &Path) -> io::Result<String> {
    String::from_utf8(read(path)?)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "stream did not contain valid UTF-8"))
}

/// The first `n` bytes of `path` (all of them when it is shorter), leaving the whole to the next [`read`]: a regular
/// file's first bytes on disk; a pipe or a terminal is read whole and kept (see the crate documentation; without
/// [`keep_pipes`], its bytes are gone once looked at).
pub fn peek(path: &Path, n: usize) -> io::Result<Vec<u8>> {
    if let Some(bytes) = kept(path) {
        return Ok(bytes[..n.min(bytes.len())].to_vec());
    }
    let mut file = open(path)?;
    if file.metadata()?.is_file() {
        let mut head = Vec::new();
        (&mut file).take(n as u64).read_to_end(&mut head)?;
        return Ok(head);
    }
    // One opening only: closing a named pipe's reading end before its writer is done would break the writer.
    let bytes = whole(file, path)?;
    Ok(bytes[..n.min(bytes.len())].to_vec())
}

/// The size in bytes of what [`read`] gives for `path`: a regular file's size on disk, a pipe's or a terminal's bytes
/// (read whole now if they were not yet, and kept as [`peek`] keeps them).
pub fn size(path: &Path) -> io::Result<u64> {
    if let Some(bytes) = kept(path) {
        return Ok(bytes.len() as u64);
    }
    let file = open(path)?;
    let meta = file.metadata()?;
    if meta.is_file() {
        return Ok(meta.len());
    }
    Ok(whole(file, path)?.len() as u64)
}

/// What a file of this type is, when it is not one to read whole; `None` for a regular file or a pipe.
fn refused(kind: &FileType) -> Option<&'static str> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return None;
        }
    }
    non_regular(kind)
}

/// What a file type is, for messages (`"a directory"`, `"a FIFO (named pipe)"`, `"a character device"`, ...); `None`
/// for a regular file. Shared with `outfile`, which refuses to replace what is not a regular file.
pub fn non_regular(kind: &FileType) -> Option<&'static str> {
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if kind.is_char_device() {
            return Some("a character device");
        }
        if kind.is_block_device() {
            return Some("a block device");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_file_is_read_whole() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let path = dir.path().join("a.txt");
        std::fs::write(&path, "v 1 2 3\n").expect("write");
        assert_eq!(read(&path).expect("read"), b"v 1 2 3\n");
        assert_eq!(read_to_string(&path).expect("read"), "v 1 2 3\n");
    }

    #[test]
    fn a_directory_is_refused_as_one() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let e = read(dir.path()).expect_err("a directory is no input");
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(e.to_string(), "a directory, not a file");
    }

    #[test]
    fn a_missing_file_keeps_the_system_error() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let e = read(&dir.path().join("missing.obj")).expect_err("missing");
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
    }

    /// `/dev/zero` never ends: read whole it would take all memory. It is refused before a byte is read.
    #[cfg(unix)]
    #[test]
    fn an_endless_device_is_refused_not_read() {
        for (path, what) in [("/dev/zero", "a character device"), ("/dev/null", "a character device")] {
            let e = read(Path::new(path)).expect_err(path);
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{path}");
            assert!(e.to_string().starts_with(what), "{path}: {e}");
        }
    }

    /// A regular file is looked at without being kept: `peek` gives its first bytes, `read` and `size` what is on
    /// disk at their own time, and `open` still streams it.
    #[test]
    fn a_regular_file_is_looked_at_and_read_from_disk() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let path = dir.path().join("a.obj");
        std::fs::write(&path, "v 1 2 3\n").expect("write");
        assert_eq!(peek(&path, 3).expect("peek"), b"v 1");
        assert_eq!(peek(&path, 100).expect("peek"), b"v 1 2 3\n");
        std::fs::write(&path, "v 4 5 6\nv 7 8 9\n").expect("write again");
        assert_eq!(read(&path).expect("read"), b"v 4 5 6\nv 7 8 9\n");
        assert_eq!(size(&path).expect("size"), 16);
        assert!(open(&path).is_ok());
        assert!(kept(&path).is_none());
    }

    /// In a process that keeps pipes, a pipe looked at (to tell what it holds) is read whole once: every later look
    /// and read of its path gets the same bytes, its size is theirs, and `open` (whose readers seek) refuses it
    /// rather than wait for a writer.
    #[cfg(unix)]
    #[test]
    fn a_pipe_looked_at_reads_as_a_file_would() {
        keep_pipes();
        let dir = tempfile::tempdir().expect("temporary directory");
        let fifo = dir.path().join("fifo.tch");
        let writer = fifo_writer(&fifo, b"TINCULL\xff and the rest");
        assert_eq!(peek(&fifo, 7).expect("peek the fifo"), b"TINCULL");
        writer.join().expect("writer");
        assert_eq!(peek(&fifo, 100).expect("peek again"), b"TINCULL\xff and the rest");
        assert_eq!(size(&fifo).expect("size"), 21);
        assert_eq!(read(&fifo).expect("read"), b"TINCULL\xff and the rest");
        assert_eq!(read(&fifo).expect("read again"), b"TINCULL\xff and the rest");
        let e = open(&fifo).expect_err("a pipe read already cannot be streamed again");
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("read already"), "{e}");
        // Text that is not UTF-8 is refused as such.
        let e = read_to_string(&fifo).expect_err("not UTF-8");
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
    }

    /// A named pipe at `path`, and a thread that writes `bytes` into it once a reader opens it.
    #[cfg(unix)]
    fn fifo_writer(path: &Path, bytes: &'static [u8]) -> std::thread::JoinHandle<()> {
        use std::io::Write;
        let status = std::process::Command::new("mkfifo")
            .arg(path)
            .status()
            .expect("mkfifo runs");
        assert!(status.success(), "mkfifo {}", path.display());
        let path = path.to_path_buf();
        std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(&path)
                .expect("open the fifo");
            f.write_all(bytes).expect("write the fifo");
        })
    }

    /// A pipe is read to its end (`<(gen)` and `/dev/stdin` fed by a pipe are inputs users give).
    #[cfg(unix)]
    #[test]
    fn a_pipe_is_read_to_its_end() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let fifo = dir.path().join("fifo");
        let writer = fifo_writer(&fifo, b"0 0 2\n");
        assert_eq!(read_to_string(&fifo).expect("read the fifo"), "0 0 2\n");
        writer.join().expect("writer");
    }
}
