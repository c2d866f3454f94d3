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

/// `read_if` reads a file of another kind no further than the bytes it was judged by (a reader checking a magic
/// number refused a 1 MB file only once it had read it whole), and reads a wanted file or pipe whole.
#[test]
fn read_if_stops_at_bytes_not_wanted() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let big = dir.path().join("big.bin");
    let mut bytes = vec![7u8; 1 << 20];
    std::fs::write(&big, &bytes).expect("write a file");
    assert_eq!(
        infile::read_if(&big, 8, |h| h == b"TINCULL\x1a").expect("read"),
        vec![7u8; 8]
    );
    assert_eq!(infile::read_if(&big, 8, |h| h == [7u8; 8]).expect("read"), bytes);
    bytes[..8].copy_from_slice(b"TINCULL\x1a");
    std::fs::write(&big, &bytes).expect("write a file");
    assert_eq!(infile::read_if(&big, 8, |h| h == b"TINCULL\x1a").expect("read"), bytes);
    let short = dir.path().join("short.bin");
    std::fs::write(&short, b"TIN").expect("write a file");
    assert_eq!(infile::read_if(&short, 8, |h| h.len() == 8).expect("read"), b"TIN");
    let fifo = dir.path().join("fifo");
    let writer = feed(&fifo, b"TINCULL\x1a and the rest");
    assert_eq!(
        infile::read_if(&fifo, 8, |h| h == b"TINCULL\x1a").expect("read"),
        b"TINCULL\x1a and the rest"
    );
    writer.join().expect("writer");
    let writer = feed(&fifo, b"NOTMAGIC");
    assert_eq!(
        infile::read_if(&fifo, 8, |h| h == b"TINCULL\x1a").expect("read"),
        b"NOTMAGIC"
    );
    writer.join().expect("writer");
}
