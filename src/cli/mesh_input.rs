//! Loading the terrain mesh that most commands take as their first argument.
//!
//! An OBJ file is imported as it is; a DEM grid (`.npy`, `.asc`, `.hgt`, `.png`, `.tif`/`.tiff`) is read with
//! [`tin::read_dem`] and simplified by greedy insertion to `--dem-vertices` vertices first (what `tincull tin` does,
//! without writing the OBJ).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use tin::{DedupePolicy, ObjImportOptions, ObjImportReport, Tin};

use super::Output;

/// How to resolve input points that share x,y but differ in z.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum DedupeArg {
    /// Reject the input with an error naming both points.
    #[default]
    Reject,
    /// Keep the highest point at each x,y.
    KeepHighest,
}

/// Which axis of an OBJ file points up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum UpArg {
    /// z is height (tincull's own frame).
    #[default]
    Z,
    /// y is height (as many 3-D tools write OBJ): rotated to z up, (x, y, z) -> (x, -z, y).
    Y,
}

impl UpArg {
    /// The importer's axis.
    pub fn axis(self) -> tin::UpAxis {
        match self {
            UpArg::Z => tin::UpAxis::Z,
            UpArg::Y => tin::UpAxis::Y,
        }
    }
}

/// The first flag given of those that apply to OBJ meshes only (`--keep-faces`, `--dedupe`, `--up`), as written on
/// the command line (a flag given is named even at its default value: it was given for a mesh).
fn mesh_flag(keep_faces: bool, dedupe: Option<DedupeArg>, up: Option<UpArg>) -> Option<String> {
    let name = |v: Option<clap::builder::PossibleValue>| v.map_or_else(String::new, |v| v.get_name().to_string());
    if keep_faces {
        Some(String::from("--keep-faces"))
    } else if let Some(dedupe) = dedupe {
        Some(format!("--dedupe {}", name(dedupe.to_possible_value())))
    } else {
        up.map(|up| format!("--up {}", name(up.to_possible_value())))
    }
}

/// The first flag given of those that apply to DEM grids only (`--z-scale`, `--spacing`, `--band`, `--dem-vertices`),
/// as written on the command line (even at its default value).
fn dem_flag(dem: &DemArgs, dem_vertices: Option<usize>) -> Option<String> {
    if let Some(z_scale) = dem.z_scale {
        Some(format!("--z-scale {}", tin::compact_number(z_scale)))
    } else if let Some((dx, dy)) = dem.spacing {
        Some(format!(
            "--spacing {},{}",
            tin::compact_number(dx),
            tin::compact_number(dy)
        ))
    } else if let Some(b) = dem.band {
        Some(format!("--band {b}"))
    } else {
        dem_vertices.map(|n| format!("--dem-vertices {n}"))
    }
}

/// An error when a flag that applies to OBJ meshes only ([`mesh_flag`]) is given for the DEM grid `path`, rather
/// than ignoring it: a DEM's samples are heights on a grid, triangulated by tincull.
pub fn refuse_mesh_flags_for_dem(
    path: &std::path::Path,
    keep_faces: bool,
    dedupe: Option<DedupeArg>,
    up: Option<UpArg>,
) -> Result<()> {
    if let Some(flag) = mesh_flag(keep_faces, dedupe, up) {
        bail!(
            "{}: {flag} applies to OBJ meshes; a DEM grid's samples are heights on a grid, triangulated by tincull",
            path.display()
        );
    }
    Ok(())
}

/// An error when a flag that applies to DEM grids only ([`dem_flag`]) is given for the OBJ mesh `path`, rather than
/// ignoring it: a mesh's vertices are used as they are.
pub fn refuse_dem_flags_for_mesh(path: &std::path::Path, dem: &DemArgs, dem_vertices: Option<usize>) -> Result<()> {
    if let Some(flag) = dem_flag(dem, dem_vertices) {
        bail!(
            "{}: {flag} applies to DEM grids (.npy, .asc, .hgt, .png, .tif); a mesh's vertices are used as they are",
            path.display()
        );
    }
    Ok(())
}

/// How to import a mesh or a DEM grid: part of [`MeshArgs`], and on its own for the commands whose input may also be
/// a hierarchy (`render`, `view`). The default: no flag given.
#[derive(Clone, Copy, Debug, Default, Args)]
pub struct ImportArgs {
    /// For a mesh input: use the file's own triangles (checked to form a height field) instead of
    /// re-triangulating its vertices.
    #[arg(long)]
    pub keep_faces: bool,
    /// For a mesh input: what to do with vertices that share x,y but differ in z [default: reject].
    #[arg(long, value_enum)]
    pub dedupe: Option<DedupeArg>,
    /// For a mesh input: the file's up axis (y for a y-up OBJ, rotated to z up on import) [default: z].
    #[arg(long, value_enum)]
    pub up: Option<UpArg>,
    /// For a DEM grid (.npy, .asc, .hgt, .png, .tif): simplify it to this many vertices first (at least 3, and at
    /// least the corners of the grid's convex hull) [default: 10000].
    #[arg(long, value_name = "N")]
    pub dem_vertices: Option<usize>,
    /// For a DEM grid: how to read it.
    #[command(flatten)]
    pub dem: DemArgs,
}

impl ImportArgs {
    /// The vertices a DEM grid is simplified to: `--dem-vertices`, or [`DEFAULT_DEM_VERTICES`].
    pub fn dem_vertices(&self) -> usize {
        self.dem_vertices.unwrap_or(DEFAULT_DEM_VERTICES)
    }

    /// The mesh arguments for `path` with these import options.
    pub fn mesh(&self, path: &std::path::Path) -> MeshArgs {
        MeshArgs {
            mesh: path.to_path_buf(),
            import: *self,
        }
    }
}

/// How to read a DEM grid: the options of every command that reads one (`tin`, `tiles plan`, and every command
/// that takes a mesh or a DEM).
#[derive(Clone, Copy, Debug, Args)]
pub struct DemArgs {
    /// A DEM grid's sample spacing `dx,dy` in metres (overrides a .npy sidecar or a GeoTIFF's georeference; required
    /// for .png and a plain TIFF).
    #[arg(long, value_parser = parse_spacing, allow_hyphen_values = true)]
    pub spacing: Option<(f64, f64)>,
    /// Multiply a DEM grid's heights by this (for .png: metres per grey level); finite and non-zero (negative
    /// flips the terrain) [default: 1].
    #[arg(long, value_name = "Z_SCALE", value_parser = parse_z_scale, allow_hyphen_values = true)]
    pub z_scale: Option<f64>,
    /// The elevation band (1-based) of a multi-band GeoTIFF.
    #[arg(long)]
    pub band: Option<u16>,
}

impl Default for DemArgs {
    /// The georeference of the file, heights as they are, the first band.
    fn default() -> Self {
        DemArgs {
            spacing: None,
            z_scale: None,
            band: None,
        }
    }
}

impl DemArgs {
    /// The reader's options.
    pub fn options(&self) -> tin::DemOptions {
        tin::DemOptions {
            spacing: self.spacing,
            z_scale: self.z_scale.unwrap_or(1.0),
            band: self.band,
        }
    }
}

fn parse_z_scale(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(z) if z.is_finite() && z != 0.0 => Ok(z),
        Ok(_) => Err(format!("{s}: the height scale must be finite and non-zero")),
        Err(_) => Err(format!("{s:?} is not a number")),
    }
}

fn parse_spacing(s: &str) -> Result<(f64, f64), String> {
    let [dx, dy] = super::values::numbers(s, "dx,dy")?;
    if !(dx > 0.0 && dy > 0.0) {
        return Err(format!("spacing must be positive and finite, got {s:?}"));
    }
    Ok((dx, dy))
}

/// Arguments naming a terrain mesh and how to import it.
#[derive(Debug, Args)]
pub struct MeshArgs {
    /// The terrain mesh (OBJ), or a DEM grid (.npy, .asc, .hgt, .png, .tif/.tiff) simplified to --dem-vertices.
    pub mesh: PathBuf,
    /// How to import it.
    #[command(flatten)]
    pub import: ImportArgs,
}

/// Default vertex budget when a command is given a DEM grid instead of a mesh.
pub const DEFAULT_DEM_VERTICES: usize = 10_000;

/// What was read when the input was a DEM grid.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemSource {
    /// Rows and columns of the grid.
    pub rows: usize,
    /// Columns of the grid.
    pub cols: usize,
    /// Sample spacing (m).
    pub spacing: (f64, f64),
    /// World x,y of the north-west sample (m).
    pub origin: [f64; 2],
    /// Void samples.
    pub voids: usize,
    /// Largest vertical error of the simplified TIN (m).
    pub max_error: f64,
    /// The GeoTIFF's CRS, units and layout, for `.tif` inputs.
    pub geotiff: Option<tin::dem::geotiff::GeoTiffInfo>,
    /// How coordinates in degrees were put into metres (a geographic GeoTIFF, or an `.asc` whose `.prj` says
    /// geographic); None when they were metres.
    pub to_metres: Option<String>,
}

/// Warns when a DEM's grid looks like degrees read as metres: spacings under a centimetre and a north-west sample
/// within ±180, ±90 (a geographic `.asc` without its `.prj`, say). Only a warning: a millimetre grid near the origin
/// is a fine terrain too.
pub fn warn_if_degrees(grid: &tin::Grid, path: &std::path::Path, out: Output) {
    let o = grid.origin;
    if grid.dx < 0.01 && grid.dy < 0.01 && o.x.abs() <= 180.0 && o.y.abs() <= 90.0 {
        out.warn(format!(
            "{}: spacing {:.3e} x {:.3e} m and a north-west sample at ({:.6}, {:.6}) look like degrees read as \
             metres; if they are degrees, put the CRS beside the grid (a .prj for .asc) or give --spacing in metres",
            path.display(),
            grid.dx,
            grid.dy,
            o.x,
            o.y
        ));
    }
}

/// Warns when a DEM's heights were taken to be in its projected CRS's feet without the file saying so (a GeoTIFF
/// without `VerticalUnitsGeoKey`, [`tin::dem::geotiff::GeoTiffInfo::heights_unit_assumed`]; an `.asc` whose `.prj` is
/// in feet and does not state the heights' unit); nothing for other files, or one whose header cannot be read (the
/// reader names that error).
pub fn warn_about_dem_file(path: &std::path::Path, opts: &tin::DemOptions, out: Output) {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let assumed = match ext.as_str() {
        "tif" | "tiff" => tin::dem::geotiff::read_geotiff_tags(path, opts)
            .ok()
            .filter(|i| i.heights_unit_assumed)
            .map(|i| (i.conversion, i.height_unit_m)),
        "asc" => tin::dem::asc::read_asc_height_unit(path, opts)
            .ok()
            .filter(|&(_, assumed)| assumed)
            .map(|(u, _)| {
                (
                    tin::dem::asc::read_asc_conversion(path, opts)
                        .ok()
                        .flatten()
                        .unwrap_or_default(),
                    u,
                )
            }),
        _ => None,
    };
    if let Some((conversion, unit)) = assumed {
        out.warn(format!(
            "{}: {conversion}; the file does not say the heights' unit, so they were taken to be in the same feet; if \
             they are metres, give --z-scale {} to undo that",
            path.display(),
            1.0 / unit
        ));
    }
}

/// Warns when a mesh, as read with `up`, looks modelled with y up ([`y_up_hint`]).
pub fn warn_if_y_up(tin: &Tin, path: &std::path::Path, up: UpArg, out: Output) {
    if let Some(hint) = y_up_hint(tin.bbox().size().to_array(), path, up) {
        out.warn(hint);
    }
}

/// A hint when a mesh of extents `size` (x, y, z), as read with `up`, looks modelled with y up (as many 3-D tools
/// export OBJ): its "north-south" extent is under a quarter of both its east-west extent and its "relief". tincull
/// reads z as height; only a hint, since a narrow strip of steep terrain looks the same. Read with `--up y`, such a
/// mesh was z-up in its file.
fn y_up_hint([x, y, z]: [f64; 3], path: &std::path::Path, up: UpArg) -> Option<String> {
    (y < 0.25 * x.min(z)).then(|| match up {
        UpArg::Z => format!(
            "{}: extents x {x:.1}, y {y:.1}, z {z:.1}: the mesh looks y-up; tincull takes z as height: give --up y \
             to read it y-up (rotated to z up), or export it with z up",
            path.display()
        ),
        UpArg::Y => format!(
            "{}: extents x {x:.1}, y {y:.1}, z {z:.1} once rotated by --up y: the file looks z-up already; leave out \
             --up y",
            path.display()
        ),
    })
}

/// The extents (x, y, z) of the `v` lines of an OBJ file, for [`y_up_hint`] once its import failed; None when the
/// file cannot be read or has no vertex.
fn read_extents(path: &std::path::Path) -> Option<[f64; 3]> {
    // A pipe's bytes are kept by `infile` from the import's read.
    let text = infile::read(path).ok()?;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for line in text.split(|&b| b == b'\n') {
        let Some(rest) = line.strip_prefix(b"v ") else { continue };
        let mut words = std::str::from_utf8(rest).ok()?.split_whitespace();
        for k in 0..3 {
            let v: f64 = words.next()?.parse().ok()?;
            (lo[k], hi[k]) = (lo[k].min(v), hi[k].max(v));
        }
    }
    let size = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    size.iter().all(|s| s.is_finite()).then_some(size)
}

/// Whether `path` names a DEM grid (by extension) rather than a mesh.
pub fn is_dem(path: &std::path::Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    matches!(ext.as_str(), "npy" | "asc" | "hgt" | "png" | "tif" | "tiff")
}

/// Whether `path` is a tincull hierarchy: named `.tch`, or starting with the `.tch` magic number whatever its name
/// (a pipe too: `infile` keeps what it read for the reader; an unreadable file is left to the reader that opens it,
/// which names the error).
pub fn is_hierarchy(path: &std::path::Path) -> bool {
    if path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("tch"))
    {
        return true;
    }
    infile::peek(path, cull::MAGIC.len()).is_ok_and(|head| head == cull::MAGIC)
}

/// What a file holds, told by its first bytes: for the errors of a command given the wrong kind of file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A tincull hierarchy (`.tch` magic number).
    Hierarchy,
    /// A tincull PVS file (`.pvs` magic number, written by `tincull pvs -o`).
    Pvs,
    /// Text whose first line that is neither blank nor a comment is an OBJ statement (`v`, `f`, `o`, ...).
    ObjText,
    /// Text starting (after blanks) with `{` or `[`: JSON, such as a `.npy` grid's sidecar or `export --export-json`.
    Json,
    /// Anything else, or a file that cannot be read.
    Other,
}

/// What `path` holds by its first bytes ([`FileKind`]; a pipe's too, which `infile` keeps for its reader);
/// [`FileKind::Other`] for what cannot be read.
pub fn file_kind(path: &std::path::Path) -> FileKind {
    let Ok(head) = infile::peek(path, 4096) else {
        return FileKind::Other;
    };
    if head.starts_with(&cull::MAGIC) {
        return FileKind::Hierarchy;
    }
    if head.starts_with(&pvs::MAGIC) {
        return FileKind::Pvs;
    }
    // The text up to the first byte that is not UTF-8 (a character cut by the 4096 bytes read, say).
    let text = match std::str::from_utf8(&head) {
        Ok(t) => t,
        Err(e) => std::str::from_utf8(&head[..e.valid_up_to()]).unwrap_or_default(),
    };
    if text.trim_start().starts_with(['{', '[']) {
        return FileKind::Json;
    }
    const STATEMENTS: [&str; 10] = ["v", "vt", "vn", "f", "o", "g", "s", "l", "mtllib", "usemtl"];
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'));
    match first.and_then(|l| l.split_whitespace().next()) {
        Some(word) if STATEMENTS.contains(&word) => FileKind::ObjText,
        _ => FileKind::Other,
    }
}

/// What a JSON file given as a terrain or a hierarchy is, for the error: the sidecar of a `.npy` grid beside it
/// (naming the grid to give instead), or JSON of another kind (a hierarchy's `export --export-json`, a tiles plan).
fn json_kind(path: &std::path::Path) -> String {
    let grid = path.with_extension("npy");
    if grid.is_file() {
        format!(
            "is the JSON sidecar of the grid {} (give that file: its sidecar is read beside it)",
            grid.display()
        )
    } else {
        "is JSON (such as a hierarchy's `export --export-json` or a tiles plan)".to_string()
    }
}

/// The name `STEM.tch` (in the working folder) for the command suggested to build a hierarchy of `path`.
fn tch_name(path: &std::path::Path) -> String {
    // In the working folder: the terrain's own folder may be read-only data.
    let name = path
        .file_stem()
        .map_or_else(|| "terrain".into(), |s| s.to_string_lossy().into_owned());
    format!("{name}.tch")
}

/// The mesh of the hierarchy read from `path` as a [`tin::Tin`] (for the exact checker and the ground under an eye);
/// a mesh that is not a valid one (a file written by hand or damaged, its checksum made to match) is an error naming
/// the file.
pub fn hierarchy_tin_of(h: &cull::Hierarchy, path: &std::path::Path) -> Result<tin::Tin> {
    eval::evaluate::hierarchy_tin(h)
        .with_context(|| format!("{}: the hierarchy's mesh is not a valid terrain mesh", path.display()))
}

/// Reads the hierarchy that a command takes as its input (`cull`, `eval`, `export`, `pvs`, `failmap`, `info`,
/// `render`, `view`): [`cull::Hierarchy::load`], and for a file that is not one, an error saying what it is (a mesh,
/// a DEM grid, a PVS file) and how to build a hierarchy of a terrain.
pub fn load_hierarchy(path: &std::path::Path) -> Result<cull::Hierarchy> {
    let error = match cull::Hierarchy::load(path) {
        Ok(h) => return Ok(h),
        Err(e) => e,
    };
    if !matches!(error.kind(), cull::HierarchyError::BadMagic) {
        return Err(error.into());
    }
    let p = path.display();
    let named_tch = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("tch"));
    match file_kind(path) {
        FileKind::Pvs => bail!(
            "{p} is a tincull PVS file (written by `tincull pvs -o`), not a hierarchy: this command reads the .tch \
             written by `tincull build`"
        ),
        FileKind::ObjText if named_tch => bail!(
            "{p} holds OBJ text (a mesh), not a tincull hierarchy, whatever its name: rename it to .obj, then build a \
             hierarchy with `tincull build MESH.obj -o MESH.tch`"
        ),
        FileKind::ObjText => bail!(
            "{p} is an OBJ mesh, not a tincull hierarchy: build one with `tincull build {p} -o {}`",
            tch_name(path)
        ),
        FileKind::Json if !is_dem(path) => bail!(
            "{p} {}, not a tincull hierarchy: this command reads the .tch written by `tincull build`",
            json_kind(path)
        ),
        _ if is_dem(path) => bail!(
            "{p} is a DEM grid, not a tincull hierarchy: build one with `tincull build {p} -o {}`",
            tch_name(path)
        ),
        _ if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("obj")) =>
        {
            bail!(
                "{p} is named as an OBJ mesh, not a tincull hierarchy: build one with `tincull build {p} -o {}`",
                tch_name(path)
            )
        }
        _ => Err(error.into()),
    }
}

impl MeshArgs {
    /// An error when a flag of how to import a mesh or a DEM grid is given while the input is a hierarchy, rather
    /// than ignoring it: a `.tch` holds its mesh as it was built.
    pub fn refuse_for_hierarchy(&self) -> Result<()> {
        self.refuse_import_flags("a hierarchy (.tch) holds its mesh as it was built")
    }

    /// An error when a flag of how to import a mesh or a DEM grid is given while the input is neither (`why` says
    /// what it is instead).
    pub fn refuse_import_flags(&self, why: &str) -> Result<()> {
        let flag = mesh_flag(self.import.keep_faces, self.import.dedupe, self.import.up)
            .map(|f| (f, "an OBJ mesh input"))
            .or_else(|| dem_flag(&self.import.dem, self.import.dem_vertices).map(|f| (f, "a DEM grid input")));
        if let Some((flag, input)) = flag {
            bail!("{}: {flag} applies to {input}; {why}", self.mesh.display());
        }
        Ok(())
    }

    /// Reads the mesh, reporting what the import did (merged duplicates, re-triangulation) as warnings.
    pub fn load(&self, out: Output) -> Result<(Tin, ObjImportReport)> {
        self.load_with_source(out).map(|(t, r, _)| (t, r))
    }

    /// [`MeshArgs::load`], also returning what was read when the input is a DEM grid.
    pub fn load_with_source(&self, out: Output) -> Result<(Tin, ObjImportReport, Option<DemSource>)> {
        // By content: a mesh named `.tch` is read as the mesh it is, and a directory so named is named as one.
        if file_kind(&self.mesh) == FileKind::Hierarchy {
            bail!(
                "{} is a tincull hierarchy (.tch), not a mesh: this command reads an OBJ mesh or a DEM grid (commands \
                 that read a hierarchy: info, cull, eval, export, pvs, failmap, render, view)",
                self.mesh.display()
            );
        }
        if file_kind(&self.mesh) == FileKind::Pvs {
            bail!(
                "{} is a tincull PVS file (written by `tincull pvs -o`), not a terrain: this command reads an OBJ mesh \
                 or a DEM grid",
                self.mesh.display()
            );
        }
        // A DEM's extension wins: raw heights (`.hgt`) may begin with the byte of `{`.
        if !is_dem(&self.mesh) && file_kind(&self.mesh) == FileKind::Json {
            bail!(
                "{} {}, not a terrain: this command reads an OBJ mesh or a DEM grid",
                self.mesh.display(),
                json_kind(&self.mesh)
            );
        }
        if is_dem(&self.mesh) {
            refuse_mesh_flags_for_dem(&self.mesh, self.import.keep_faces, self.import.dedupe, self.import.up)?;
            return self.load_dem(out);
        }
        refuse_dem_flags_for_mesh(&self.mesh, &self.import.dem, self.import.dem_vertices)?;
        let opts = ObjImportOptions {
            keep_faces: self.import.keep_faces,
            dedupe: match self.import.dedupe.unwrap_or_default() {
                DedupeArg::Reject => DedupePolicy::Reject,
                DedupeArg::KeepHighest => DedupePolicy::KeepHighest,
            },
            up: self.import.up.unwrap_or_default().axis(),
        };
        let spinner = out.spinner("reading mesh");
        let (tin, report) = tin::read_obj(&self.mesh, &opts).map_err(|e| {
            // A y-up mesh usually fails as vertical walls: say why, from the file's extents.
            // The file's extents as read with `up` (rotated to z up: (x, y, z) -> (x, -z, y)).
            let up = self.import.up.unwrap_or_default();
            let read = |[x, y, z]: [f64; 3]| if up == UpArg::Y { [x, z, y] } else { [x, y, z] };
            match read_extents(&self.mesh).and_then(|size| y_up_hint(read(size), &self.mesh, up)) {
                Some(hint) => anyhow::anyhow!("{e}\n{hint}"),
                None => e.into(),
            }
        })?;
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
        if report.unreferenced_dropped > 0 {
            out.warn(format!(
                "{}: dropped {} vertices that no face uses (--keep-faces keeps the file's triangles only; a file cut \
                 short loses the faces after the cut)",
                self.mesh.display(),
                report.unreferenced_dropped
            ));
        }
        if report.unterminated {
            out.warn(format!(
                "{}: the file does not end with a line break, as a file cut short would not: its last line may be \
                 cut (check its size against the original's)",
                self.mesh.display()
            ));
        }
        warn_if_y_up(&tin, &self.mesh, self.import.up.unwrap_or_default(), out);
        Ok((tin, report, None))
    }

    /// Reads a DEM grid and simplifies it to `dem_vertices` vertices.
    fn load_dem(&self, out: Output) -> Result<(Tin, ObjImportReport, Option<DemSource>)> {
        if !(3..=u32::MAX as usize).contains(&self.import.dem_vertices()) {
            bail!(
                "{}: --dem-vertices must be at least 3 and fit in 32 bits (at most 4294967295), got {}",
                self.mesh.display(),
                self.import.dem_vertices()
            );
        }
        let opts = self.import.dem.options();
        let spinner = out.spinner("reading DEM");
        let ext = self
            .mesh
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let (grid, geotiff, to_metres) = match ext.as_deref() {
            Some("tif" | "tiff") => {
                let (g, i) = tin::dem::geotiff::read_geotiff_info(&self.mesh, &opts)?;
                let to_metres = Some(i.conversion.clone()).filter(|c| !c.is_empty());
                (g, Some(i), to_metres)
            }
            Some("asc") => (
                tin::read_dem(&self.mesh, &opts)?,
                None,
                tin::dem::asc::read_asc_conversion(&self.mesh, &opts)?,
            ),
            _ => (tin::read_dem(&self.mesh, &opts)?, None, None),
        };
        spinner.finish_and_clear();
        warn_if_degrees(&grid, &self.mesh, out);
        warn_about_dem_file(&self.mesh, &opts, out);
        let bar = out.progress(self.import.dem_vertices() as u64, "simplifying DEM");
        let progress = |v: usize| bar.set_position(v as u64);
        let simplify = tin::SimplifyOptions {
            max_vertices: Some(self.import.dem_vertices()),
            max_error: None,
        };
        let (tin, simplified) =
            tin::simplify(&grid, &simplify, Some(&progress)).with_context(|| self.mesh.display().to_string())?;
        bar.finish_and_clear();
        out.warn(format!(
            "{} is a DEM grid ({} x {} samples, {} voids): simplified to {} vertices (max error {:.3} m); \
             `tincull tin` writes the mesh with more control",
            self.mesh.display(),
            grid.rows,
            grid.cols,
            grid.voids(),
            simplified.vertices,
            simplified.max_error
        ));
        let report = ObjImportReport {
            vertices: tin.num_vertices(),
            triangles: tin.num_triangles(),
            ..Default::default()
        };
        let source = DemSource {
            rows: grid.rows,
            cols: grid.cols,
            spacing: (grid.dx, grid.dy),
            origin: grid.origin.to_array(),
            voids: grid.voids(),
            max_error: simplified.max_error,
            geotiff,
            to_metres,
        };
        Ok((tin, report, Some(source)))
    }
}
