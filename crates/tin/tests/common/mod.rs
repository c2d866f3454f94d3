//! Helpers shared by the DEM reader tests (each test binary uses some of them).
#![allow(dead_code)]

use std::path::Path;

/// Writes a `.npy` file with the given header fields and raw data.
pub fn write_npy(path: &Path, version: u8, descr: &str, fortran: bool, shape: &str, data: &[u8]) {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    let prefix = if version == 1 { 10 } else { 12 };
    let mut header = dict.into_bytes();
    while (prefix + header.len() + 1) % 64 != 0 {
        header.push(b' ');
    }
    header.push(b'\n');
    let mut bytes = b"\x93NUMPY".to_vec();
    bytes.push(version);
    bytes.push(0);
    if version == 1 {
        bytes.extend((header.len() as u16).to_le_bytes());
    } else {
        bytes.extend((header.len() as u32).to_le_bytes());
    }
    bytes.extend(header);
    bytes.extend(data);
    std::fs::write(path, bytes).expect("write npy");
}

/// Where the entry of `tag` starts in the first IFD of a little-endian classic TIFF.
pub fn ifd_entry(b: &[u8], tag: u16) -> Option<usize> {
    assert_eq!(&b[..4], b"II*\0", "a little-endian classic TIFF");
    let ifd = u32::from_le_bytes(b[4..8].try_into().expect("4 bytes")) as usize;
    (0..usize::from(u16::from_le_bytes([b[ifd], b[ifd + 1]])))
        .map(|i| ifd + 2 + 12 * i)
        .find(|&e| u16::from_le_bytes([b[e], b[e + 1]]) == tag)
}
