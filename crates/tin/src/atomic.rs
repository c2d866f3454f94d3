//! Writing output files so that a reader never sees a half-written one: write a temporary file in the same
//! directory, flush it to disk, then rename it over the target (atomic on POSIX file systems).

use std::fs::{self, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Result, TinError};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `path` through `write`, atomically: either the complete new file is there afterwards, or the old file
/// (or none) and an error. The temporary file (`.NAME.PID.N.tmp` next to the target) is removed on failure.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| TinError::io(path, io::Error::new(io::ErrorKind::InvalidInput, "not a file name")))?
        .to_string_lossy()
        .into_owned();
    let mut write = Some(write);
    for _ in 0..1000 {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.{}.{n}.tmp", std::process::id()));
        let file = match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => f,
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(TinError::io(path, e)),
        };
        let Some(write) = write.take() else { break };
        let result = (|| {
            let mut w = BufWriter::new(file);
            write(&mut w)?;
            let file = w.into_inner().map_err(|e| e.into_error())?;
            file.sync_all()?;
            drop(file);
            fs::rename(&tmp, path)
        })();
        return result.map_err(|e| {
            let _ = fs::remove_file(&tmp);
            TinError::io(path, e)
        });
    }
    Err(TinError::io(
        path,
        io::Error::new(
            io::ErrorKind::AlreadyExists,
            "could not create a temporary file next to it",
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_file_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.txt");
        fs::write(&path, "old").expect("write");
        write_atomic(&path, |w| w.write_all(b"new")).expect("atomic write");
        assert_eq!(fs::read_to_string(&path).expect("read"), "new");
        assert_eq!(fs::read_dir(dir.path()).expect("list").count(), 1);
    }

    #[test]
    fn failed_write_keeps_old_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.txt");
        fs::write(&path, "old").expect("write");
        let err = write_atomic(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("disk full"))
        });
        assert!(matches!(err, Err(TinError::Io { .. })));
        assert_eq!(fs::read_to_string(&path).expect("read"), "old");
        assert_eq!(fs::read_dir(dir.path()).expect("list").count(), 1);
    }

    #[test]
    fn missing_directory_is_an_io_error() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("no/such/dir/out.txt");
        assert!(matches!(write_atomic(&path, |_| Ok(())), Err(TinError::Io { .. })));
    }
}
