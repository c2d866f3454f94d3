//! `tincull demo`: the main job on the bundled default terrain: build, evaluate, report, and write `out/`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use super::build_cmd::{print_report, stage_progress};
use super::eval_cmd::{add_outputs, check_outputs};
use super::files::Outputs;
use super::mesh_input::ImportArgs;
use super::{Output, OutputArgs};
use cull::Hierarchy;
use eval::evaluate::{EvalOptions, evaluate, hierarchy_tin};
use pipeline::export::to_json;
use pipeline::{BuildParams, build};
use tin::Tin;

/// The bundled default terrain.
pub const DEFAULT_MESH: &str = "meshes/jacksboro-10k.obj";

/// Arguments of `tincull demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// The terrain (default: the bundled jacksboro-10k, a 10,000-vertex TIN of a public-domain USGS DEM:
    /// meshes/jacksboro-10k.obj in the working folder, else in the source tree the binary was built from).
    pub mesh: Option<PathBuf>,
    /// Directory for the outputs.
    #[arg(long, default_value = "out")]
    pub out_dir: PathBuf,
    /// Viewpoints per class for the evaluation, 1 to 1000000.
    #[arg(long, default_value_t = 10)]
    pub viewpoints: usize,
    /// How to import the mesh.
    #[command(flatten)]
    pub import: ImportArgs,
    /// Output flags.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Runs `tincull demo`.
pub fn run(args: &DemoArgs, out: Output) -> Result<()> {
    let mut out = out;
    let mesh = match &args.mesh {
        Some(m) => m.clone(),
        None => default_mesh()?,
    };
    super::eval_cmd::check_viewpoints(args.viewpoints)?;
    if args.out_dir == Path::new("-") {
        anyhow::bail!(
            "--out-dir -: the demo writes several files (the hierarchy, its JSON, the grouped OBJ and .mtl, the \
             evaluation, renders) into a directory, which standard output cannot hold; give a directory name"
        );
    }
    if args.out_dir.exists() && !args.out_dir.is_dir() {
        anyhow::bail!("--out-dir {}: exists and is not a directory", args.out_dir.display());
    }
    if !args.out_dir.exists() && args.out_dir.is_symlink() {
        anyhow::bail!(
            "--out-dir {}: a symbolic link to nothing (its target does not exist); give a directory",
            args.out_dir.display()
        );
    }
    // The folders made here are removed again if the demo fails or is interrupted (they are then empty: the outputs
    // are all or nothing). Made, and the outputs checked, before the terrain is read.
    let new_dirs = outfile::NewDir::create_all(&args.out_dir)
        .with_context(|| format!("--out-dir {}: cannot create it", args.out_dir.display()))?;
    let stem = mesh
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "terrain".into());
    let path = |suffix: &str| args.out_dir.join(format!("{stem}{suffix}"));
    let mut files = Outputs::new();
    files.input(&mesh)?;
    files.check(&path(".tch"))?;
    files.check(&path(".json"))?;
    files.check_grouped_obj(&path("-groups.obj"), "--out-dir")?;
    check_outputs(
        &mut files,
        Some(&path("-eval.json")),
        Some(&path("-eval.csv")),
        &mut out,
    )?;
    // The renders come after the rest (they need a GPU adapter, and are left out without one), but a path that
    // cannot take them is refused before any work as the others are.
    files.check(&path("-map.png"))?;
    files.check(&path("-culling.png"))?;

    let (tin, _) = args.import.mesh(&mesh).load(out)?;
    let params = BuildParams::default();
    out.say(format!("tincull demo on {}", mesh.display()));
    out.say(format!(
        "build with defaults: {} sectors x {} subsectors, seeds one per 200 triangles, min group {}, {} orphan passes",
        params.sectors, params.subsectors, params.crystal.min_group, params.crystal.orphan_passes
    ));

    let result = build(&tin, &params, Some(stage_progress(out)))?;
    print_report(&result.report, out);
    files.add_bytes(&path(".tch"), &result.hierarchy.to_bytes()?)?;
    files.add_bytes(&path(".json"), to_json(&result.hierarchy)?.as_bytes())?;
    files.add_grouped_obj(&result.hierarchy, &path("-groups.obj"))?;

    let h = &result.hierarchy;
    let htin = hierarchy_tin(h)?;
    let opts = EvalOptions {
        viewpoints: args.viewpoints,
        ..EvalOptions::default()
    };
    let bar = out.progress((opts.viewpoints * opts.classes.len()) as u64, "evaluating");
    let e = evaluate(h, &htin, &opts, &|done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    out.say(format!(
        "\naccuracy against ground truth ({} viewpoints per class, 360° view; ground truth is a lower bound of the \
         visible set):",
        opts.viewpoints
    ));
    out.say(e.table());
    add_outputs(&mut files, &e, Some(&path("-eval.json")), Some(&path("-eval.csv")))?;
    files.commit()?;
    new_dirs.keep();
    let renders = match write_renders(h, &htin, &path("-map.png"), &path("-culling.png")) {
        Ok(eye) => format!(
            ", {stem}-map.png (groups, orphans grey) and {stem}-culling.png (valley eye at {:.0}, {:.0}, {:.0}: \
             drawn groups solid, culled ones wireframe)",
            eye[0], eye[1], eye[2]
        ),
        Err(e) => {
            out.say(format!("no renders: {e:#}"));
            String::new()
        }
    };
    out.say(format!(
        "wrote {}: {stem}.tch (hierarchy), {stem}.json, {stem}-groups.obj/.mtl (groups for Blender or MeshLab), \
         {stem}-eval.csv/.json{renders}",
        args.out_dir.display()
    ));
    let mut report = serde_json::to_value(&result.report)?;
    report["evaluation"] = serde_json::to_value(&e.rows)?;
    report["out_dir"] = serde_json::to_value(&args.out_dir)?;
    out.json(&report)
}

/// Renders the groups map and an orbit view of the culling from a valley viewpoint; returns that viewpoint.
/// Fails (and the demo goes on without images) when no GPU adapter, not even a software one, is available.
#[cfg(feature = "viewer")]
fn write_renders(h: &Hierarchy, htin: &Tin, map: &Path, culling: &Path) -> Result<[f64; 3]> {
    use truth::{ViewpointClass, viewpoints};
    use viewer::{Gpu, RenderOptions, Terrain, ViewKind};
    let gpu = Gpu::headless()?;
    let terrain = Terrain::from_hierarchy(h.clone())?;
    let image = viewer::render(&gpu, &terrain, &RenderOptions::default())?.image;
    viewer::write_png(map, &image)?;
    let eye = viewpoints(htin, ViewpointClass::Valley, 1, 1)
        .first()
        .map(|e| e.to_array())
        .context("no valley viewpoint on this terrain")?;
    let options = RenderOptions {
        view: ViewKind::Orbit,
        eye: Some(eye),
        ..RenderOptions::default()
    };
    viewer::write_png(culling, &viewer::render(&gpu, &terrain, &options)?.image)?;
    Ok(eye)
}

/// Without the viewer there are no renders: the demo says so and writes everything else.
#[cfg(not(feature = "viewer"))]
fn write_renders(_: &Hierarchy, _: &Tin, _: &Path, _: &Path) -> Result<[f64; 3]> {
    Err(super::no_viewer("the demo's renders"))
}

/// The bundled terrain, found relative to the working directory or to the source tree the binary was built from;
/// an error saying so when neither holds it (a binary copied elsewhere).
fn default_mesh() -> Result<PathBuf> {
    bundled_mesh(
        Path::new(DEFAULT_MESH),
        &Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_MESH),
    )
}

/// The first of `local` and `source` that is a file, or the error of [`default_mesh`].
fn bundled_mesh(local: &Path, source: &Path) -> Result<PathBuf> {
    match [local, source].into_iter().find(|p| p.is_file()) {
        Some(found) => Ok(found.to_path_buf()),
        None => anyhow::bail!(
            "the bundled terrain {DEFAULT_MESH} is neither in the working folder nor at {} (the source tree this \
             binary was built from): run the demo from the repository, or give a mesh (`tincull demo MESH.obj`)",
            source.display()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A binary copied away from its source tree, run outside the repository, says where it looked and what to do.
    #[test]
    fn a_missing_bundled_mesh_is_a_clear_error() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (local, source) = (dir.path().join("a.obj"), dir.path().join("b.obj"));
        let e = bundled_mesh(&local, &source).unwrap_err().to_string();
        assert!(
            e.contains(&source.display().to_string()) && e.contains("give a mesh"),
            "{e}"
        );
        std::fs::write(&source, "v 0 0 0\n").expect("write");
        assert_eq!(bundled_mesh(&local, &source).expect("found"), source);
        std::fs::write(&local, "v 0 0 0\n").expect("write");
        assert_eq!(bundled_mesh(&local, &source).expect("found"), local);
    }
}
