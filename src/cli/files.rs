//! The outputs of one command, through the project's one writer (the `outfile` crate): every path is checked before
//! the work starts (directory exists, not a directory, writable, a regular file or none; symlinks followed), the
//! contents are written to temporary files, and all are renamed at the end, so a command that fails leaves none of
//! its outputs. `-` is standard output where a command allows it (one output, and then the command's own text goes
//! to stderr or nowhere).

use std::io::{self, IsTerminal, Write};
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use cull::Hierarchy;
use pipeline::export::{mtl_path, write_grouped_obj_to, write_mtl_to};
use pipeline::gltf::{bin_path, gltf_files, is_glb};

use super::Output;

/// The checked outputs of one command, written all or nothing by [`Outputs::commit`].
#[derive(Default)]
pub struct Outputs {
    batch: outfile::Batch,
    stdout: Option<Vec<u8>>,
    /// The flag whose output goes to standard output (`-`), once one does.
    stdout_flag: Option<String>,
}

impl Outputs {
    /// No outputs yet.
    pub fn new() -> Outputs {
        Outputs::default()
    }

    /// Declares a file the command reads: no output may be that file (checked whichever is declared first), nor a
    /// file that its reader may read beside it when it is a DEM (a `.npy` grid's JSON sidecar, an `.asc` grid's
    /// `.prj`, a GeoTIFF's `.msk`: [`tin::dem::companion_files`]).
    pub fn input(&mut self, path: &Path) -> Result<()> {
        self.batch.input(path)?;
        for companion in tin::dem::companion_files(path) {
            self.batch.input(&companion)?;
        }
        Ok(())
    }

    /// Checks a file output (before the work).
    pub fn check(&mut self, path: &Path) -> Result<()> {
        Ok(self.batch.check(path)?)
    }

    /// Checks a file output that cannot be `-` (standard output): given `-`, an error naming `flag` and saying `why`
    /// (the output is binary, several files, or standard output carries the command's report), and to give a file.
    pub fn check_file(&mut self, path: &Path, flag: &str, why: &str) -> Result<()> {
        if path == Path::new("-") {
            bail!("{flag} -: {why}; give a file name");
        }
        self.check(path)
    }

    /// Checks an output that may be `-` (standard output). With `-`, `out` stops printing text and `--json` is
    /// refused (both would go to standard output).
    pub fn check_or_stdout(&mut self, path: &Path, flag: &str, out: &mut Output) -> Result<()> {
        if path != Path::new("-") {
            return self.check(path);
        }
        if out.json {
            bail!("{flag} - and --json both write to standard output; give a file to one of them");
        }
        if let Some(first) = &self.stdout_flag {
            bail!("{first} - and {flag} - both write to standard output; give a file to one of them");
        }
        self.stdout_flag = Some(flag.to_string());
        out.quiet_text = true;
        Ok(())
    }

    /// [`Outputs::check_or_stdout`] for a binary output (a `.tch`): `-` is refused when standard output is a
    /// terminal, which binary bytes would garble.
    pub fn check_binary_or_stdout(&mut self, path: &Path, flag: &str, out: &mut Output) -> Result<()> {
        if path == Path::new("-") && io::stdout().is_terminal() {
            bail!(
                "{flag} -: a hierarchy is binary and standard output is a terminal; redirect it (`{flag} - > FILE`) or \
                 give a file"
            );
        }
        self.check_or_stdout(path, flag, out)
    }

    /// Checks a grouped OBJ output (given with `flag`) and its `.mtl` (refused when the OBJ is named like its
    /// `.mtl`, or is `-`: two files).
    pub fn check_grouped_obj(&mut self, obj: &Path, flag: &str) -> Result<()> {
        if obj == Path::new("-") {
            bail!(
                "{flag} -: the OBJ is written with its materials (.mtl) beside it, two files that standard output \
                 cannot hold; give a file name (OUT.obj, and OUT.mtl is written beside it)"
            );
        }
        let (mtl, _) = mtl_path(obj)?;
        refuse_other_format(obj, "an OBJ mesh (with its .mtl)", "obj")?;
        self.check(obj)?;
        self.check(&mtl)
    }

    /// Checks a glTF output (given with `flag`): named `.glb` (one binary file) or `.gltf` (with its `.bin` beside
    /// it, also checked).
    pub fn check_gltf(&mut self, path: &Path, flag: &str) -> Result<()> {
        // The name's format first: `--export-gltf x.mtl` beside `--export-obj x.obj` is a wrong name, not a clash.
        refuse_other_formats(path, "glTF", &["glb", "gltf"])?;
        self.check_file(
            path,
            flag,
            "glTF is written as a binary .glb, or as a .gltf with its .bin beside it (two files)",
        )?;
        if !is_glb(path) {
            self.check(&bin_path(path)?.0)?;
        }
        Ok(())
    }

    /// Adds the glTF of `h` (and its `.bin` for a `.gltf`); returns the files it adds.
    pub fn add_gltf(&mut self, h: &Hierarchy, path: &Path) -> Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        for (p, bytes) in gltf_files(h, path)? {
            self.add_bytes(&p, &bytes)?;
            written.push(p);
        }
        Ok(written)
    }

    /// Writes the content of a checked output to its temporary file (or keeps it for standard output).
    pub fn add(&mut self, path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
        if path == Path::new("-") && self.stdout_flag.is_some() {
            let mut bytes = Vec::new();
            write(&mut bytes)?;
            self.stdout = Some(bytes);
            return Ok(());
        }
        Ok(self.batch.add(path, write)?)
    }

    /// [`Outputs::add`] with bytes.
    pub fn add_bytes(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.add(path, |w| w.write_all(bytes))
    }

    /// Adds the grouped OBJ of `h` and its `.mtl`.
    pub fn add_grouped_obj(&mut self, h: &Hierarchy, obj: &Path) -> Result<PathBuf> {
        let (mtl, name) = mtl_path(obj)?;
        self.add(&mtl, |w| write_mtl_to(h, w))?;
        self.add(obj, |w| write_grouped_obj_to(h, &name, w))?;
        Ok(mtl)
    }

    /// Renames every file output over its target, then writes standard output's content.
    pub fn commit(self) -> Result<()> {
        self.batch.commit()?;
        if let Some(bytes) = self.stdout {
            let mut out = io::stdout().lock();
            out.write_all(&bytes)?;
            out.flush()?;
        }
        Ok(())
    }
}

/// Writes one output now (checked, atomic); `-` is not allowed.
pub fn write_one(path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
    let mut o = Outputs::new();
    o.check(path)?;
    o.add(path, write)?;
    o.commit()
}

/// The file formats tincull reads or writes that it tells apart by their name's extension.
const KNOWN_EXTENSIONS: [&str; 15] = [
    "obj", "mtl", "npy", "asc", "hgt", "png", "tif", "tiff", "tch", "pvs", "json", "csv", "glb", "gltf", "bin",
];

/// An error when the output `path` of a command that writes `what` (whose extension is `own`) is named with the
/// extension of another format that tincull knows (`tin -o t.npy`, `build -o b.obj`, `export --export-json b.tch`):
/// the file would later be read as that format, and an existing file of that format (another hierarchy, the mesh)
/// would be replaced by something else. Other names (and `-`) are left to the user.
pub fn refuse_other_format(path: &Path, what: &str, own: &str) -> Result<()> {
    refuse_other_formats(path, what, &[own])
}

/// An error unless the image output `path` (of `what`: `render`, `--screenshot`, …) is named `.png`: the images
/// are PNG whatever the name, and another name would hide that.
pub fn require_png(path: &Path, what: &str) -> Result<()> {
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        bail!("{}: {what} writes a PNG image; name it .png", path.display());
    }
    Ok(())
}

/// [`refuse_other_format`] for an output that may take any of the extensions `own` (glTF: `.glb` or `.gltf`).
pub fn refuse_other_formats(path: &Path, what: &str, own: &[&str]) -> Result<()> {
    let Some(ext) = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase) else {
        return Ok(());
    };
    if !own.contains(&ext.as_str()) && KNOWN_EXTENSIONS.contains(&ext.as_str()) {
        let names: Vec<String> = own.iter().map(|e| format!(".{e}")).collect();
        bail!(
            "{}: this command writes {what}, which a .{ext} name would make read as another format; name it {}",
            path.display(),
            names.join(" or ")
        );
    }
    Ok(())
}
