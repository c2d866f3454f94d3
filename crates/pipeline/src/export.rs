//! Content for people and other tools: the grouped OBJ (one `g group_N` per leaf group, `g orphans`) with a `.mtl`
//! of distinct colours, and the hierarchy's JSON form.
//!
//! This crate writes no files: these functions write to any [`Write`], and the command line and the viewer put
//! them in files with the project's one output writer (the `outfile` crate: paths checked before the work, atomic
//! replacement, the OBJ and its `.mtl` all or nothing).

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use cull::Hierarchy;

use crate::ExportError;
use crate::palette::{ORPHAN_COLOUR, group_colour};

/// The `.mtl` written beside a grouped OBJ (`obj` with the extension `mtl`) and the name the OBJ refers to it by.
/// Refused when it would be the OBJ itself (`--obj same.mtl`), so that the export never overwrites its own materials.
pub fn mtl_path(obj: &Path) -> Result<(PathBuf, String), ExportError> {
    let refuse = |reason| ExportError::Path {
        path: obj.to_path_buf(),
        reason,
    };
    let mtl = obj.with_extension("mtl");
    if mtl == obj {
        return Err(refuse(
            "the grouped OBJ's materials go to the same path with the extension .mtl, which is this file; give the \
             OBJ another extension (e.g. .obj)",
        ));
    }
    let name = mtl
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| refuse("the OBJ path has no file name"))?;
    Ok((mtl, name))
}

/// Writes the `.mtl` of a grouped OBJ: one material per leaf group (in triangle order), grey for orphans.
pub fn write_mtl_to(h: &Hierarchy, w: &mut dyn Write) -> io::Result<()> {
    writeln!(w, "# tincull groups: one material per leaf group, grey for orphans")?;
    for i in 0..h.leaf_ranges().len() {
        let [r, g, b] = group_colour(i);
        writeln!(w, "newmtl group_{i}\nKd {r:.4} {g:.4} {b:.4}\n")?;
    }
    let [r, g, b] = ORPHAN_COLOUR;
    writeln!(w, "newmtl orphans\nKd {r:.4} {g:.4} {b:.4}")
}

/// Writes the hierarchy's mesh as OBJ with one group per leaf (in triangle order) and the orphans last (when there
/// are any), using the materials of `mtl_name` (see [`write_mtl_to`]). Positions are written exactly (shortest
/// round-trip f64 text).
///
/// # Panics
/// When the hierarchy's ranges do not fit its mesh: give it one that passes [`Hierarchy::check_invariants`] (every
/// loaded or built one does).
pub fn write_grouped_obj_to(h: &Hierarchy, mtl_name: &str, w: &mut dyn Write) -> io::Result<()> {
    let leaves = h.leaf_ranges();
    writeln!(
        w,
        "# tincull hierarchy mesh: {} vertices, {} triangles, {} groups, {} orphans",
        h.mesh.positions.len(),
        h.mesh.triangles.len(),
        leaves.len(),
        h.always_visible[1] - h.always_visible[0]
    )?;
    writeln!(w, "mtllib {mtl_name}")?;
    for p in &h.mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    let faces = |w: &mut dyn Write, [s, e]: [u32; 2]| -> io::Result<()> {
        for t in &h.mesh.triangles[s as usize..e as usize] {
            writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
        }
        Ok(())
    };
    for (i, &range) in leaves.iter().enumerate() {
        writeln!(w, "g group_{i}\nusemtl group_{i}")?;
        faces(w, range)?;
    }
    // A quadtree has no orphans: no empty group.
    if h.always_visible[0] < h.always_visible[1] {
        writeln!(w, "g orphans\nusemtl orphans")?;
    }
    faces(w, h.always_visible)
}

/// The hierarchy's JSON form: the same content as the `.tch` file, for people and notebooks.
pub fn to_json(h: &Hierarchy) -> Result<String, ExportError> {
    serde_json::to_string(h).map_err(ExportError::json("cannot encode the hierarchy as JSON"))
}

/// Parses the JSON form, checking every structural invariant of the hierarchy.
pub fn from_json(text: &str) -> Result<Hierarchy, ExportError> {
    let h: Hierarchy =
        serde_json::from_str(text).map_err(ExportError::json("cannot decode the hierarchy's JSON form"))?;
    h.check_invariants()?;
    Ok(h)
}
