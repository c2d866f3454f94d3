//! What a file is, told from its first bytes: for the errors that say what to do with a file given to a reader of
//! another format (a GeoTIFF given as a mesh, a mesh given as a DEM, a DEM read through a pipe, whose name says
//! nothing).

use std::io::Read;
use std::path::Path;

/// How many leading bytes [`sniff`] looks at.
pub const HEAD: usize = 512;

/// A file format told from its first bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sniffed {
    /// A TIFF (a GeoTIFF DEM, maybe).
    Tiff,
    /// A PNG image.
    Png,
    /// A NumPy `.npy` array.
    Npy,
    /// An ESRI ASCII grid (`ncols` first).
    AsciiGrid,
    /// A Wavefront OBJ mesh (a vertex line before anything but comments and blank lines).
    Obj,
    /// gzip or zip.
    Compressed,
    /// A binary glTF.
    Gltf,
    /// A PLY mesh.
    Ply,
    /// An ASCII STL mesh.
    Stl,
}

/// The format that `head` (a file's first bytes, [`HEAD`] of them or the whole file) starts like, if one is known.
pub fn sniff(head: &[u8]) -> Option<Sniffed> {
    let starts = |magic: &[u8]| head.starts_with(magic);
    // Classic TIFF (42) and BigTIFF (43), either byte order.
    let tiff = [b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"].iter().any(|m| starts(*m));
    Some(if tiff {
        Sniffed::Tiff
    } else if starts(b"\x89PNG\r\n\x1a\n") {
        Sniffed::Png
    } else if starts(b"\x93NUMPY") {
        Sniffed::Npy
    } else if starts(b"\x1f\x8b") || starts(b"PK\x03\x04") {
        Sniffed::Compressed
    } else if starts(b"glTF") {
        Sniffed::Gltf
    } else if starts(b"ply\n") || starts(b"ply\r\n") {
        Sniffed::Ply
    } else if starts(b"solid ") && head.windows(5).any(|w| w == b"facet") {
        Sniffed::Stl
    } else {
        let first = head
            .split(|&b| b == b'\n')
            .map(|line| line.trim_ascii())
            .find(|line| !line.is_empty() && !line.starts_with(b"#"))?;
        if first.len() >= 5 && first[..5].eq_ignore_ascii_case(b"ncols") {
            Sniffed::AsciiGrid
        } else if first.starts_with(b"v ") || first.starts_with(b"v\t") {
            Sniffed::Obj
        } else {
            return None;
        }
    })
}

/// The first [`HEAD`] bytes of the file at `path` (fewer for a shorter file), or `None` when it cannot be read. Reads
/// them from a pipe too, which they are then gone from: for error messages only.
pub fn head_of(path: &Path) -> Option<Vec<u8>> {
    let mut head = Vec::with_capacity(HEAD);
    std::fs::File::open(path)
        .ok()?
        .take(HEAD as u64)
        .read_to_end(&mut head)
        .ok()?;
    Some(head)
}

impl Sniffed {
    /// What to do with a file of this format that was given where a DEM grid is read (by its extension).
    pub fn as_dem_hint(self) -> &'static str {
        match self {
            Sniffed::Tiff => "it starts like a TIFF: name it .tif or .tiff to read it as a DEM (GeoTIFF)",
            Sniffed::Png => "it starts like a PNG: name it .png to read it as a height map (with --spacing)",
            Sniffed::Npy => {
                "it starts like a NumPy array: name it .npy (its .json sidecar beside it) to read it as a DEM"
            }
            Sniffed::AsciiGrid => "it starts like an ESRI ASCII grid: name it .asc to read it as a DEM",
            Sniffed::Obj => {
                "it starts like an OBJ mesh, which is not a DEM grid: the commands that read meshes (build, \
                 info, …) take it, named .obj, as it is"
            }
            Sniffed::Compressed => "it starts like a compressed file (gzip or zip): unpack it first",
            Sniffed::Gltf => "it starts like a binary glTF mesh: tincull reads DEM grids and OBJ meshes",
            Sniffed::Ply => "it starts like a PLY mesh: tincull reads DEM grids and OBJ meshes",
            Sniffed::Stl => "it starts like an ASCII STL mesh: tincull reads DEM grids and OBJ meshes",
        }
    }

    /// What to do with a file of this format that was given where an OBJ mesh is read; `None` for an OBJ.
    pub fn as_mesh_hint(self) -> Option<&'static str> {
        Some(match self {
            Sniffed::Tiff => "a TIFF: name it .tif or .tiff to read it as a DEM (GeoTIFF)",
            Sniffed::Png => "a PNG: name it .png to read it as a height map (with --spacing)",
            Sniffed::Npy => "a NumPy array: name it .npy to read it as a DEM",
            Sniffed::AsciiGrid => "an ESRI ASCII grid: name it .asc to read it as a DEM",
            Sniffed::Compressed => "compressed (gzip or zip): unpack it first",
            Sniffed::Gltf => "a binary glTF: tincull reads OBJ meshes; convert it to OBJ",
            Sniffed::Ply => "a PLY mesh: tincull reads OBJ meshes; convert it to OBJ",
            Sniffed::Stl => "an ASCII STL mesh: tincull reads OBJ meshes; convert it to OBJ",
            Sniffed::Obj => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_told_from_their_first_bytes() {
        let cases: [(&[u8], Option<Sniffed>); 14] = [
            (b"II*\0\x08\0\0\0", Some(Sniffed::Tiff)),
            (b"MM\0*\0\0\0\x08", Some(Sniffed::Tiff)),
            (b"II+\0\x08\0\0\0", Some(Sniffed::Tiff)),
            (b"MM\0+\0\x08\0\0", Some(Sniffed::Tiff)),
            (b"\x89PNG\r\n\x1a\n....", Some(Sniffed::Png)),
            (b"\x93NUMPY\x01\0", Some(Sniffed::Npy)),
            (b"NCOLS 403\nnrows 344\n", Some(Sniffed::AsciiGrid)),
            (b"# made by hand\n\nv 0 0 1\nv 1 0 2\n", Some(Sniffed::Obj)),
            (b"\x1f\x8b\x08\0", Some(Sniffed::Compressed)),
            (b"glTF\x02\0\0\0", Some(Sniffed::Gltf)),
            (b"ply\nformat ascii 1.0\n", Some(Sniffed::Ply)),
            (b"solid t\n facet normal 0 0 1\n", Some(Sniffed::Stl)),
            (b"f 1 2 3\n", None),
            (b"", None),
        ];
        for (head, want) in cases {
            assert_eq!(sniff(head), want, "{:?}", String::from_utf8_lossy(head));
        }
        assert_eq!(Sniffed::Obj.as_mesh_hint(), None);
    }
}
