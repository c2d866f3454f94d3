//! The checksummed files a plan writes beside itself for its jobs (a mesh tile's part, a DEM tile's far field):
//! a value in postcard, framed like a `.tch` ([`cull::file::encode_framed`]: magic, version, length, CRC-32).

use std::path::Path;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::TilesError;

/// `value` as a framed file; `what` names it in errors.
pub(crate) fn encode<T: Serialize>(
    magic: &[u8; 8],
    version: u32,
    value: &T,
    what: &str,
) -> Result<Vec<u8>, TilesError> {
    cull::file::encode_framed(magic, version, value)
        .map_err(|e| TilesError::Parameter(format!("cannot encode {what}: {e}")))
}

/// Reads a framed file written by [`encode`] with the same magic and version; errors name `path` and say what is
/// wrong (`what` names the kind of file).
pub(crate) fn decode<T: DeserializeOwned>(
    bytes: &[u8],
    magic: &[u8; 8],
    version: u32,
    path: &Path,
    what: &'static str,
) -> Result<T, TilesError> {
    let bad = |reason: String| TilesError::TileFile {
        path: path.to_path_buf(),
        what,
        reason,
    };
    let (found, payload) = cull::file::unframe(bytes, magic).map_err(|e| bad(e.to_string()))?;
    if found != version {
        return Err(bad(format!("{what} version {found} is not {version}")));
    }
    cull::file::decode(payload).map_err(|e| bad(format!("malformed {what}: {e}")))
}

/// Reads the file at `path` whole.
pub(crate) fn read(path: &Path) -> Result<Vec<u8>, TilesError> {
    infile::read(path).map_err(|source| TilesError::Io {
        path: path.to_path_buf(),
        source,
    })
}
