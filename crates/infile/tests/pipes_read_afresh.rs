//! A process that does not call `infile::keep_pipes` (a library user: a renderer loading hierarchies through the C
//! API) reads a pipe afresh every time, and a path that names a regular file later is read from disk. Its own test
//! binary, so that no other test has turned keeping on in the process.

#![cfg(unix)]

use std::io::Write;
use std::path::Path;

/// Makes a named pipe at `path` if there is none, and a thread that writes `bytes` into it once a reader opens it.
fn feed(path: &Path, bytes: &'static [u8]) -> std::thread::JoinHandle<()> {
    if !path.exists() {
        let status = std::process::Command::new("mkfifo")
            .arg(path)
            .status()
            .expect("mkfifo runs");
        assert!(status.success(), "mkfifo {}", path.display());
    }
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .expect("open the fifo");
        f.write_all(bytes).expect("write the fifo");
    })
}

/// Regression: the bytes of the first pipe read at a path were kept for the whole process, so a renderer that loaded
/// a hierarchy from a pipe got the first one again at every later load of that path, even once the path named a
/// regular file.
#[test]
fn every_read_of_a_pipe_reads_it_afresh_unless_kept() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let fifo = dir.path().join("fifo.tch");
    let writer = feed(&fifo, b"first");
    assert_eq!(infile::read(&fifo).expect("read the fifo"), b"first");
    writer.join().expect("writer");
    let writer = feed(&fifo, b"second, longer");
    assert_eq!(infile::read(&fifo).expect("read the fifo again"), b"second, longer");
    writer.join().expect("writer");
    std::fs::remove_file(&fifo).expect("remove the fifo");
    std::fs::write(&fifo, b"a regular file now").expect("write a file");
    assert_eq!(infile::read(&fifo).expect("read the file"), b"a regular file now");
    assert_eq!(infile::size(&fifo).expect("its size"), 18);
}
