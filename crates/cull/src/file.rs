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
//! Version 2 added [`crate::BuildInfo::grouping`], the last field of the payload. A version-1 payload is therefore a
//! version-2 payload without it, and reads as one with [`crate::Grouping::Crystal`] (variant 0, encoded as the single
//! byte 0) appended; every version-1 file was crystal-grouped.
//!
//! Anything after the payload, or after the hierarchy inside the payload, is rejected as foreign. This crate reads
//! files but writes none: [`Hierarchy::to_bytes`] is the file's content, and the writer is the embedder's (tincull's
//! is the `outfile` crate: atomic replacement, symlinks followed, non-regular targets refused).

use std::path::Path;

use crate::error::HierarchyError;

/// Bytes before the payload in a framed file: magic, version, payload length, checksum.
pub const HEADER_LEN: usize = 8 + 4 + 8 + 4;

/// Why framed bytes were refused by [`unframe`] (the caller names the file and checks the version).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// The bytes do not start with the expected magic number.
    BadMagic,
    /// Fewer bytes than the header, or than the header and the payload length it declares (the file is truncated,
    /// or its length field corrupt).
    Truncated {
        /// Bytes the whole file needs: [`HEADER_LEN`] when it is shorter than its header, else the header's and the
        /// payload length it declares (always more than [`HEADER_LEN`]).
        expected: u64,
        /// Bytes of the whole file.
        found: u64,
    },
    /// This many bytes follow the payload.
    Trailing(u64),
    /// The payload's CRC-32 differs from the stored one.
    Checksum {
        /// Checksum in the header.
        stored: u32,
        /// Checksum of the payload.
        found: u32,
    },
}

impl std::fmt::Display for FrameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameError::BadMagic => write!(f, "it does not start with the expected magic number"),
            FrameError::Truncated { expected, found } => f.write_str(&truncation("", *expected, *found)),
            FrameError::Trailing(extra) => write!(f, "{extra} unexpected bytes after the data"),
            FrameError::Checksum { stored, found } => {
                write!(f, "checksum mismatch (stored {stored:08x}, computed {found:08x})")
            }
        }
    }
}

impl std::error::Error for FrameError {}

/// What [`FrameError::Truncated`] says, starting with "truncated" and then `file` (as " hierarchy file"): a file
/// shorter than its header, or one shorter than the length its header declares (truncated, or the length field
/// corrupt, as a declared length far beyond any file is).
pub(crate) fn truncation(file: &str, expected: u64, found: u64) -> String {
    if found == 0 {
        format!("empty{file} (0 bytes)")
    } else if expected == HEADER_LEN as u64 {
        format!("truncated{file}: {found} bytes, fewer than the {HEADER_LEN} of its header")
    } else {
        format!("truncated or corrupt{file}: its header declares {expected} bytes, the file has {found}")
    }
}

/// Frames `payload` as a file of this layout: `magic`, `version`, payload length, CRC-32 (IEEE) of the payload, the
/// payload (little-endian). Shared by every binary file of tincull (`.tch` here, `.pvs` in the `pvs` crate).
pub fn frame(magic: &[u8; 8], version: u32, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_LEN + payload.len());
    out.resize(HEADER_LEN, 0);
    out.extend_from_slice(payload);
    fill_header(magic, version, out)
}

/// `value` in postcard, framed as [`frame`] frames a payload, encoded straight after room for the header: one buffer
/// the size of the file, not a payload and its framed copy.
pub fn encode_framed<T: serde::Serialize + ?Sized>(
    magic: &[u8; 8],
    version: u32,
    value: &T,
) -> Result<Vec<u8>, postcard::Error> {
    let out = postcard::to_extend(value, vec![0u8; HEADER_LEN])?;
    Ok(fill_header(magic, version, out))
}

/// Writes the header of a frame into the first [`HEADER_LEN`] bytes of `out`, whose payload follows them.
fn fill_header(magic: &[u8; 8], version: u32, mut out: Vec<u8>) -> Vec<u8> {
    let (head, payload) = out.split_at_mut(HEADER_LEN);
    head[..8].copy_from_slice(magic);
    head[8..12].copy_from_slice(&version.to_le_bytes());
    head[12..20].copy_from_slice(&(payload.len() as u64).to_le_bytes());
    head[20..24].copy_from_slice(&crc32fast::hash(payload).to_le_bytes());
    out
}

/// Decodes a whole postcard payload (as [`unframe`] gives it): bytes the decoder leaves over are refused as foreign, as
/// bytes after the payload are. The error is the message to show.
pub fn decode<T: serde::de::DeserializeOwned>(payload: &[u8]) -> Result<T, String> {
    let (value, rest) = postcard::take_from_bytes(payload).map_err(|e| e.to_string())?;
    if rest.is_empty() {
        Ok(value)
    } else {
        Err(format!(
            "{} unexpected bytes after the data, inside the payload",
            rest.len()
        ))
    }
}

/// The version and payload of bytes written by [`frame`] with `magic`, after checking the magic, the length (no
/// byte missing, none after the payload) and the checksum.
pub fn unframe<'a>(bytes: &'a [u8], magic: &[u8; 8]) -> Result<(u32, &'a [u8]), FrameError> {
    // Empty: said as such rather than as a wrong magic number.
    if bytes.is_empty() {
        return Err(FrameError::Truncated {
            expected: HEADER_LEN as u64,
            found: 0,
        });
    }
    if bytes.len() < magic.len() || bytes[..magic.len()] != magic[..] {
        return Err(FrameError::BadMagic);
    }
    if bytes.len() < HEADER_LEN {
        return Err(FrameError::Truncated {
            expected: HEADER_LEN as u64,
            found: bytes.len() as u64,
        });
    }
    let word = |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let mut len = [0u8; 8];
    len.copy_from_slice(&bytes[12..20]);
    let len = u64::from_le_bytes(len);
    let payload = &bytes[HEADER_LEN..];
    if (payload.len() as u64) < len {
        return Err(FrameError::Truncated {
            expected: len.saturating_add(HEADER_LEN as u64),
            found: bytes.len() as u64,
        });
    }
    if payload.len() as u64 > len {
        return Err(FrameError::Trailing(payload.len() as u64 - len));
    }
    let (stored, found) = (word(20), crc32fast::hash(payload));
    if found != stored {
        return Err(FrameError::Checksum { stored, found });
    }
    Ok((word(8), payload))
}
use crate::hierarchy::Hierarchy;

/// The magic number that starts every `.tch` file.
pub const MAGIC: [u8; 8] = *b"TINCULL\x1a";
/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 2;
/// The oldest format version this build reads.
pub const OLDEST_READABLE_VERSION: u32 = 1;

impl Hierarchy {
    /// Encodes the hierarchy as `.tch` bytes, as it is: the invariants that [`Hierarchy::from_bytes`] checks are not
    /// checked here. A hierarchy from a build or a load holds them; one changed by hand may not, and its bytes are
    /// then refused when read. Call [`Hierarchy::check_invariants`] first to find out before writing.
    pub fn to_bytes(&self) -> Result<Vec<u8>, HierarchyError> {
        encode_framed(&MAGIC, FORMAT_VERSION, self).map_err(|e| HierarchyError::Decode(e.to_string()))
    }

    /// Decodes `.tch` bytes, checking magic, version, length, checksum and every structural invariant.
    pub fn from_bytes(bytes: &[u8]) -> Result<Hierarchy, HierarchyError> {
        let (version, payload) = unframe(bytes, &MAGIC).map_err(|e| match e {
            FrameError::BadMagic => HierarchyError::BadMagic,
            FrameError::Truncated { expected, found } => HierarchyError::Truncated { expected, found },
            FrameError::Trailing(extra) => HierarchyError::Invalid(format!("{extra} unexpected bytes after the data")),
            FrameError::Checksum { stored, found } => HierarchyError::Checksum { stored, found },
        })?;
        if !(OLDEST_READABLE_VERSION..=FORMAT_VERSION).contains(&version) {
            return Err(HierarchyError::UnsupportedVersion {
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        let upgraded;
        let payload = if version == 1 {
            // The version-2 encoding of the same hierarchy: `BuildInfo::grouping = Grouping::Crystal` appended.
            upgraded = [payload, &[0u8]].concat();
            &upgraded[..]
        } else {
            payload
        };
        // `decode` also refuses a version-2 payload framed as version 1, which would otherwise decode with its own
        // grouping, the appended byte left over.
        let h: Hierarchy = decode(payload).map_err(HierarchyError::Decode)?;
        h.check_invariants()?;
        Ok(h)
    }

    /// Reads a `.tch` file; every error names it ([`HierarchyError::InFile`], or [`HierarchyError::Io`], also for a
    /// device or a directory, which is refused rather than read: see the `infile` crate). The other way,
    /// [`Hierarchy::to_bytes`] gives what to write.
    pub fn load(path: impl AsRef<Path>) -> Result<Hierarchy, HierarchyError> {
        let path = path.as_ref();
        // A file of another kind is refused by its first bytes, not read whole first.
        let bytes = infile::read_if(path, MAGIC.len(), |head| head == MAGIC).map_err(|source| HierarchyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Hierarchy::from_bytes(&bytes).map_err(|error| HierarchyError::InFile {
            path: path.to_path_buf(),
            error: Box::new(error),
        })
    }
}
