//! Loading the terrain mesh that most commands take as their first argument.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::{Args, ValueEnum};
use tin::{DedupePolicy, ObjImportOptions, ObjImportReport, Tin};

use super::Output;

/// How to resolve input points that share x,y but differ in z.
#[derive(Clone, Copy, Debug, Default, ValueEnum)]
pub enum DedupeArg {
    /// Reject the input with an error naming both points.
    #[default]
    Reject,
    /// Keep the highest point at each x,y.
    KeepHighest,
}

/// How to import a mesh, for commands whose input may be a mesh or a hierarchy (`render`, `view`): the same
/// `--keep-faces` and `--dedupe` as every command that reads a mesh.
#[derive(Clone, Copy, Debug, Default, Args)]
pub struct ImportArgs {
    /// For a mesh input: use the file's own triangles (checked to form a height field) instead of
    /// re-triangulating its vertices.
    #[arg(long)]
    pub keep_faces: bool,
    /// For a mesh input: what to do with vertices that share x,y but differ in z.
    #[arg(long, value_enum, default_value_t = DedupeArg::Reject)]
    pub dedupe: DedupeArg,
}

impl ImportArgs {
    /// The mesh arguments for `path` with these import options.
    pub fn mesh(&self, path: &std::path::Path) -> MeshArgs {
        MeshArgs {
            mesh: path.to_path_buf(),
            keep_faces: self.keep_faces,
            dedupe: self.dedupe,
        }
    }
}

/// Arguments naming a terrain mesh and how to import it.
#[derive(Debug, Args)]
pub struct MeshArgs {
    /// The terrain mesh (OBJ).
    pub mesh: PathBuf,
    /// Use the file's own triangles (checked to form a height field) instead of re-triangulating its vertices.
    #[arg(long)]
    pub keep_faces: bool,
    /// What to do with vertices that share x,y but differ in z.
    #[arg(long, value_enum, default_value_t = DedupeArg::Reject)]
    pub dedupe: DedupeArg,
}

impl MeshArgs {
    /// Reads the mesh, reporting what the import did (merged duplicates, re-triangulation) as warnings.
    pub fn load(&self, out: Output) -> Result<(Tin, ObjImportReport)> {
        let ext = self
            .mesh
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        if matches!(ext.as_str(), "npy" | "asc" | "hgt" | "png") {
            bail!(
                "{} is a DEM grid; turn it into a mesh first with `tincull tin {} -o MESH.obj --vertices N`",
                self.mesh.display(),
                self.mesh.display()
            );
        }
        let opts = ObjImportOptions {
            keep_faces: self.keep_faces,
            dedupe: match self.dedupe {
                DedupeArg::Reject => DedupePolicy::Reject,
                DedupeArg::KeepHighest => DedupePolicy::KeepHighest,
            },
        };
        let spinner = out.spinner("reading mesh");
        let (tin, report) = tin::read_obj(&self.mesh, &opts)?;
        spinner.finish_and_clear();
        if report.merged_duplicates > 0 {
            out.warn(format!(
                "merged {} duplicate vertices (same x, y and z)",
                report.merged_duplicates
            ));
        }
        if report.dropped_lower > 0 {
            out.warn(format!(
                "dropped {} lower vertices sharing x,y with a higher one (--dedupe keep-highest)",
                report.dropped_lower
            ));
        }
        Ok((tin, report))
    }
}
