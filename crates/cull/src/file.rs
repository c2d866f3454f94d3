//! The `.tch` file: a versioned, checksummed binary container for a [`Hierarchy`]. (Its JSON form lives in the
//! `pipeline` crate, `pipeline::export::to_json`, so that this crate needs no JSON library.)
//!
//! Layout (little-endian):
//!
//! | bytes | content |
//! | --- | --- |
//! | 8 | magic `TINCULL\x1a` |
//! | 4 | format version ([`FORMAT_VERSION`]) |
//! | 8 | payload length `n` |
//! | 4 | CRC-32 (IEEE) of the payload |
//! | n | the [`Hierarchy`] encoded with postcard |
//!
//! Anything after the payload is rejected as foreign. This crate reads files but writes none: [`Hierarchy::to_bytes`]
//! is the file's content, and the writer is the embedder's (tincull's is the `outfile` crate: atomic replacement,
//! symlinks followed, non-regular targets refused).

use std::path::Path;

use crate::error::HierarchyError;
use crate::hierarchy::Hierarchy;

/// The magic number that starts every `.tch` file.
pub const MAGIC: [u8; 8] = *b"TINCULL\x1a";
/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;
const HEADER_LEN: usize = 8 + 4 + 8 + 4;

impl Hierarchy {
    /// Encodes the hierarchy as `.tch` bytes.
    pub fn to_bytes(&self) -> Result<Vec<u8>, HierarchyError> {
        let payload = postcard::to_stdvec(self).map_err(|e| HierarchyError::Decode(e.to_string()))?;
        let mut out = Vec::with_capacity(HEADER_LEN + payload.len());
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        Ok(out)
    }

    /// Decodes `.tch` bytes, checking magic, version, length, checksum and every structural invariant.
    pub fn from_bytes(bytes: &[u8]) -> Result<Hierarchy, HierarchyError> {
        if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
            return Err(HierarchyError::BadMagic);
        }
        if bytes.len() < HEADER_LEN {
            return Err(HierarchyError::Truncated {
                expected: HEADER_LEN as u64,
                found: bytes.len() as u64,
            });
        }
        let word = |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
        let version = word(8);
        if version != FORMAT_VERSION {
            return Err(HierarchyError::UnsupportedVersion {
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        let mut len = [0u8; 8];
        len.copy_from_slice(&bytes[12..20]);
        let len = u64::from_le_bytes(len);
        let stored = word(20);
        let payload = &bytes[HEADER_LEN..];
        if (payload.len() as u64) < len {
            return Err(HierarchyError::Truncated {
                expected: len,
                found: payload.len() as u64,
            });
        }
        if payload.len() as u64 > len {
            return Err(HierarchyError::Invalid(format!(
                "{} unexpected bytes after the data",
                payload.len() as u64 - len
            )));
        }
        let found = crc32fast::hash(payload);
        if found != stored {
            return Err(HierarchyError::Checksum { stored, found });
        }
        let h: Hierarchy = postcard::from_bytes(payload).map_err(|e| HierarchyError::Decode(e.to_string()))?;
        h.check_invariants()?;
        Ok(h)
    }

    /// Reads a `.tch` file.
    pub fn load(path: &Path) -> Result<Hierarchy, HierarchyError> {
        let bytes = std::fs::read(path).map_err(|source| HierarchyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Hierarchy::from_bytes(&bytes)
    }
}
