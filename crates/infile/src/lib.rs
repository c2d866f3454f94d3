//! The one opener of every tincull input file (meshes, DEMs, `.tch`, `.pvs`, tile plans, eye lists, configs), and
//! the one description of a file type in messages ([`non_regular`]).
//!
//! A path given as an input is read whole, so what it names must end: a regular file, a pipe (`<(gen)`,
//! `/dev/stdin` fed by a pipe or a file) or a terminal (typed input, to Ctrl-D). Any other character or block device
//! (`/dev/zero`, `/dev/urandom`, a disk), a socket or a directory is refused with an error of kind [`std::io::ErrorKind::InvalidInput`] that
//! says what it is: read whole, `/dev/zero` would grow a buffer until the machine runs out of memory. The kind is
//! taken from the opened file itself (`fstat`), not from the path, so a link or a rename between the check and the
//! read changes nothing. The callers name the path in their own errors.

#![warn(missing_docs)]

use std::fs::{File, FileType};
use std::io::{self, Read};
use std::path::Path;

/// Opens `path` for reading, refusing what is not a regular file, a pipe or a terminal (see the crate documentation).
pub fn open(path: &Path) -> io::Result<File> {
    use std::io::IsTerminal;
    let file = File::open(path)?;
    match refused(&file.metadata()?.file_type()) {
        None => Ok(file),
        Some(_) if file.is_terminal() => Ok(file),
        Some(what) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{what}, not a file"),
        )),
    }
}

/// Reads the whole of `path` ([`open`]'s rules).
pub fn read(path: &Path) -> io::Result<Vec<u8>> {
    let mut file = open(path)?;
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// Reads the whole of `path` as UTF-8 text ([`open`]'s rules; text that is not UTF-8 is an
/// [`io::ErrorKind::InvalidData`] error).
pub fn read_to_string(path: &Path) -> io::Result<String> {
    let mut file = open(path)?;
    let mut text = String::new();
    file.read_to_string(&mut text)?;
    Ok(text)
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

    /// A pipe is read to its end (`<(gen)` and `/dev/stdin` fed by a pipe are inputs users give).
    #[cfg(unix)]
    #[test]
    fn a_pipe_is_read_to_its_end() {
        use std::io::Write;
        let dir = tempfile::tempdir().expect("temporary directory");
        let fifo = dir.path().join("fifo");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo runs");
        assert!(status.success(), "mkfifo {}", fifo.display());
        let writer = {
            let fifo = fifo.clone();
            std::thread::spawn(move || {
                let mut f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(&fifo)
                    .expect("open the fifo");
                f.write_all(b"0 0 2\n").expect("write the fifo");
            })
        };
        assert_eq!(read_to_string(&fifo).expect("read the fifo"), "0 0 2\n");
        writer.join().expect("writer");
    }
}
