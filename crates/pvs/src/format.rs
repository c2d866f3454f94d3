//! The `.pvs` file: the PVS of many viewcells in a compact, versioned, checksummed binary form.
//!
//! Layout: the frame of `.tch` files ([`cull::file::frame`]) with magic [`MAGIC`] and version [`FORMAT_VERSION`]; the
//! payload is a [`PvsFile`] encoded with postcard. Node ids
//! are stored as differences from the previous one and ranges as (gap from the previous end, length) pairs, all
//! postcard varints, so a PVS of a few hundred ranges takes a few hundred bytes. This crate encodes and decodes; the
//! writer is the caller's (tincull's is the `outfile` crate).

use cull::file::{FrameError, decode, unframe};
use serde::{Deserialize, Serialize};

use crate::{CellPvs, PvsError, PvsParams, ViewCell};

/// The magic number that starts every `.pvs` file.
pub const MAGIC: [u8; 8] = *b"TINCPVS\x1a";
/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// One viewcell's PVS as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellRecord {
    /// The viewcell.
    pub cell: ViewCell,
    /// The top of the cell box used (m).
    pub ztop: f64,
    /// Node ids, each as its difference from the previous one.
    node_deltas: Vec<u32>,
    /// Ranges as (gap from the previous range's end, length) pairs.
    range_deltas: Vec<u32>,
}

impl CellRecord {
    /// The record of `pvs` for `cell`.
    pub fn new(cell: ViewCell, pvs: &CellPvs) -> CellRecord {
        let mut prev = 0u32;
        let node_deltas = pvs
            .nodes
            .iter()
            .map(|&n| {
                let d = n - prev;
                prev = n;
                d
            })
            .collect();
        let mut end = 0u32;
        let mut range_deltas = Vec::with_capacity(2 * pvs.ranges.len());
        for r in &pvs.ranges {
            range_deltas.push(r[0] - end);
            range_deltas.push(r[1] - r[0]);
            end = r[1];
        }
        CellRecord {
            cell,
            ztop: pvs.ztop,
            node_deltas,
            range_deltas,
        }
    }

    /// The hierarchy nodes of the PVS, increasing.
    pub fn nodes(&self) -> Vec<u32> {
        let mut at = 0u32;
        self.node_deltas
            .iter()
            .map(|&d| {
                at = at.saturating_add(d);
                at
            })
            .collect()
    }

    /// The triangle ranges of the PVS, increasing.
    pub fn ranges(&self) -> Vec<[u32; 2]> {
        let mut end = 0u32;
        self.range_deltas
            .chunks_exact(2)
            .map(|c| {
                let s = end.saturating_add(c[0]);
                end = s.saturating_add(c[1]);
                [s, end]
            })
            .collect()
    }

    /// Bytes of this record in the file.
    pub fn encoded_len(&self) -> usize {
        postcard::to_stdvec(self).map_or(0, |v| v.len())
    }
}

/// The content of a `.pvs` file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PvsFile {
    /// Triangles of the hierarchy the ranges refer to.
    pub triangles: u32,
    /// Nodes of that hierarchy.
    pub nodes: u32,
    /// The parameters used.
    pub params: PvsParams,
    /// One record per viewcell.
    pub cells: Vec<CellRecord>,
}

impl PvsFile {
    /// Encodes the file's bytes.
    pub fn to_bytes(&self) -> Result<Vec<u8>, PvsError> {
        cull::file::encode_framed(&MAGIC, FORMAT_VERSION, self).map_err(|e| PvsError::BadFile(e.to_string()))
    }

    /// Decodes a file's bytes, checking magic, version, length, checksum, every cell (a finite, non-empty rectangle
    /// and height band, a finite top) and that every range lies within the triangles and every node id within the
    /// nodes.
    pub fn from_bytes(bytes: &[u8]) -> Result<PvsFile, PvsError> {
        let bad = |m: String| Err(PvsError::BadFile(m));
        let (version, payload) = match unframe(bytes, &MAGIC) {
            Ok(framed) => framed,
            Err(FrameError::BadMagic) => return bad("it does not start with the PVS magic number".into()),
            Err(e @ FrameError::Truncated { .. }) => return bad(e.to_string()),
            Err(FrameError::Trailing(extra)) => return bad(format!("{extra} unexpected bytes after the data")),
            Err(FrameError::Checksum { .. }) => return bad("checksum mismatch".into()),
        };
        if version != FORMAT_VERSION {
            return bad(format!("format version {version}, this build reads {FORMAT_VERSION}"));
        }
        let file: PvsFile = decode(payload).map_err(PvsError::BadFile)?;
        for (i, c) in file.cells.iter().enumerate() {
            if let Err(e) = c.cell.validate() {
                return bad(format!("cell {i}: {e}"));
            }
            if !c.ztop.is_finite() {
                return bad(format!("cell {i}: its top {} is not finite", c.ztop));
            }
            if c.range_deltas.len() % 2 != 0 || c.ranges().iter().any(|r| r[1] > file.triangles) {
                return bad(format!("cell {i} has ranges beyond the {} triangles", file.triangles));
            }
            if c.nodes().last().is_some_and(|&n| n >= file.nodes) {
                return bad(format!("cell {i} names nodes beyond the {} nodes", file.nodes));
            }
        }
        Ok(file)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Height;

    #[test]
    fn round_trip_and_rejections() {
        let pvs = CellPvs {
            nodes: vec![0, 3, 7],
            ranges: vec![[0, 10], [20, 25], [100, 130]],
            ztop: 12.5,
            ..CellPvs::default()
        };
        let cell = ViewCell {
            rect: [0.0, 0.0, 50.0, 50.0],
            height: Height::AboveGround([0.0, 2.0]),
        };
        let rec = CellRecord::new(cell, &pvs);
        assert_eq!(rec.nodes(), pvs.nodes);
        assert_eq!(rec.ranges(), pvs.ranges);
        let file = PvsFile {
            triangles: 130,
            nodes: 8,
            params: PvsParams::default(),
            cells: vec![rec],
        };
        let bytes = file.to_bytes().expect("encodes");
        assert_eq!(PvsFile::from_bytes(&bytes).expect("decodes"), file);
        let mut bad = bytes.clone();
        let last = bad.len() - 1;
        bad[last] ^= 1;
        assert!(PvsFile::from_bytes(&bad).is_err());
        assert!(PvsFile::from_bytes(&bytes[..10]).is_err());
        // Bytes left inside the payload (framed with a matching checksum) are refused too.
        let mut payload = bytes[cull::file::HEADER_LEN..].to_vec();
        payload.push(0);
        let padded = cull::file::frame(&MAGIC, FORMAT_VERSION, &payload);
        let e = PvsFile::from_bytes(&padded).expect_err("a byte left over");
        assert!(e.to_string().contains("1 unexpected bytes"), "{e}");
        let short = PvsFile {
            triangles: 100,
            ..file.clone()
        };
        assert!(PvsFile::from_bytes(&short.to_bytes().expect("encodes")).is_err());
        let few_nodes = PvsFile {
            nodes: 7,
            ..file.clone()
        };
        let e = PvsFile::from_bytes(&few_nodes.to_bytes().expect("encodes")).expect_err("node 7 of 7");
        assert!(e.to_string().contains("cell 0 names nodes beyond the 7 nodes"), "{e}");
        // Cells that no computation makes (written by hand, their checksum made to match) are refused by name.
        for (rect, ztop, needle) in [
            (
                [f64::NAN, 0.0, 50.0, 50.0],
                12.5,
                "cell 0: invalid viewcell: the rectangle NaN,0,50,50 must be finite",
            ),
            (
                [0.0, 0.0, -1e300, 50.0],
                12.5,
                "cell 0: invalid viewcell: the rectangle 0,0,-1e300,50 must be finite",
            ),
            (
                [0.0, 0.0, 50.0, 50.0],
                f64::INFINITY,
                "cell 0: its top inf is not finite",
            ),
        ] {
            let mut odd = file.clone();
            odd.cells[0].cell.rect = rect;
            odd.cells[0].ztop = ztop;
            let e = PvsFile::from_bytes(&odd.to_bytes().expect("encodes")).expect_err("a cell no one computes");
            assert!(e.to_string().contains(needle), "{e}");
        }
    }
}
