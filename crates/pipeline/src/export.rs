//! Writers for people and other tools: the grouped OBJ (one `g group_N` per leaf group, `g orphans`) with a `.mtl`
//! of distinct colours, and the hierarchy's JSON form.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use cull::Hierarchy;

use tin::write_atomic;

use crate::palette::{ORPHAN_COLOUR, group_colour};

/// Writes the hierarchy's mesh as OBJ with one group per leaf (in triangle order) and the orphans last, plus a
/// `.mtl` beside it with a colour per group. Positions are written exactly (shortest round-trip f64 text).
pub fn write_grouped_obj(h: &Hierarchy, path: &Path) -> Result<()> {
    let mtl_path = path.with_extension("mtl");
    let mtl_name = mtl_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .context("the OBJ path has no file name")?;
    let leaves = h.leaf_ranges();
    write_atomic(&mtl_path, |w| {
        writeln!(w, "# tincull groups: one material per leaf group, grey for orphans")?;
        for (i, _) in leaves.iter().enumerate() {
            let [r, g, b] = group_colour(i);
            writeln!(w, "newmtl group_{i}\nKd {r:.4} {g:.4} {b:.4}\n")?;
        }
        let [r, g, b] = ORPHAN_COLOUR;
        writeln!(w, "newmtl orphans\nKd {r:.4} {g:.4} {b:.4}")?;
        Ok(())
    })?;
    Ok(write_atomic(path, |w| {
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
        let faces = |w: &mut dyn Write, [s, e]: [u32; 2]| -> std::io::Result<()> {
            for t in &h.mesh.triangles[s as usize..e as usize] {
                writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
            }
            Ok(())
        };
        for (i, &range) in leaves.iter().enumerate() {
            writeln!(w, "g group_{i}\nusemtl group_{i}")?;
            faces(w, range)?;
        }
        writeln!(w, "g orphans\nusemtl orphans")?;
        faces(w, h.always_visible)?;
        Ok(())
    })?)
}

/// The hierarchy's JSON form: the same content as the `.tch` file, for people and notebooks.
pub fn to_json(h: &Hierarchy) -> Result<String> {
    Ok(serde_json::to_string(h)?)
}

/// Parses the JSON form, checking every structural invariant of the hierarchy.
pub fn from_json(text: &str) -> Result<Hierarchy> {
    let h: Hierarchy = serde_json::from_str(text).context("cannot decode the hierarchy's JSON form")?;
    h.check_invariants()?;
    Ok(h)
}

/// Writes the hierarchy's JSON form atomically.
pub fn write_json(h: &Hierarchy, path: &Path) -> Result<()> {
    let text = to_json(h)?;
    Ok(write_atomic(path, |w| w.write_all(text.as_bytes()))?)
}
