//! Rule 6: an interrupted command leaves no temporary file. Its own test binary: [`outfile::remove_temporaries`]
//! keeps the registry locked for good, as the process is about to exit.

use std::fs;

#[test]
fn remove_temporaries_removes_every_staged_file() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let mut batch = outfile::Batch::new();
    for name in ["a.tch", "b.json"] {
        let path = dir.path().join(name);
        batch.check(&path).expect("check");
        batch.add(&path, |w| w.write_all(b"content")).expect("staged");
    }
    let temporaries = || {
        fs::read_dir(dir.path())
            .expect("list")
            .filter(|e| {
                e.as_ref()
                    .expect("entry")
                    .file_name()
                    .to_string_lossy()
                    .starts_with(".tincull-")
            })
            .count()
    };
    assert_eq!(temporaries(), 2, "both contents wait in temporary files");
    outfile::remove_temporaries();
    assert_eq!(temporaries(), 0);
    assert!(!dir.path().join("a.tch").exists() && !dir.path().join("b.json").exists());
    // The process would exit now; the batch is never dropped (its temporary files would unregister, and the
    // registry stays locked).
    std::mem::forget(batch);
}
