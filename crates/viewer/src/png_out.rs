//! PNG files: writing with the project's output writer (the `outfile` crate: the path checked, atomic replacement,
//! symlinks followed, non-regular targets refused) and reading back for tests and comparisons. Images are 8-bit RGBA.

use std::path::Path;

use crate::error::{Result, ViewerError};
use crate::render::RgbaImage;

/// Encodes `image` as an 8-bit RGBA PNG.
pub fn encode_png(image: &RgbaImage) -> std::result::Result<Vec<u8>, String> {
    let expected = image.width as usize * image.height as usize * 4;
    if image.pixels.len() != expected {
        return Err(format!(
            "the image has {} bytes, {}x{} RGBA needs {expected}",
            image.pixels.len(),
            image.width,
            image.height
        ));
    }
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, image.width, image.height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::High);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(&image.pixels).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Writes `image` to `path` as PNG, atomically (`-` is standard output).
pub fn write_png(path: &Path, image: &RgbaImage) -> Result<()> {
    let bytes = encode_png(image).map_err(|message| ViewerError::Png {
        path: path.to_path_buf(),
        message,
    })?;
    Ok(outfile::write_bytes(path, &bytes)?)
}

/// Reads a PNG as 8-bit RGBA (grey, RGB, palette and 16-bit images are converted).
pub fn read_png(path: &Path) -> Result<RgbaImage> {
    let png_error = |message: String| ViewerError::Png {
        path: path.to_path_buf(),
        message,
    };
    let file = infile::open(path).map_err(|source| ViewerError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(|e| png_error(e.to_string()))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| png_error("the image is too large".into()))?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| png_error(e.to_string()))?;
    buf.truncate(info.buffer_size());
    let (width, height) = (info.width, info.height);
    let pixels = match info.color_type {
        png::ColorType::Rgba => buf,
        png::ColorType::Rgb => buf.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect(),
        png::ColorType::Grayscale => buf.iter().flat_map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::GrayscaleAlpha => buf.chunks_exact(2).flat_map(|p| [p[0], p[0], p[0], p[1]]).collect(),
        png::ColorType::Indexed => return Err(png_error("indexed colour was not expanded".into())),
    };
    Ok(RgbaImage { width, height, pixels })
}
