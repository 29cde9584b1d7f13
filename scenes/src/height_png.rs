//! Grayscale PNG height maps: 16-bit (or 8-bit) grey levels, top image row = largest Y.

use std::path::Path;

use crate::SceneError;

/// Read a grayscale PNG as `(nx, ny, values)` with `values[j * nx + i]`, row j = 0 at
/// the smallest Y (the image's bottom row).
pub fn read(origin: &str, file: &Path) -> Result<(usize, usize, Vec<u16>), SceneError> {
    let fail = |reason: String| SceneError::HeightImage {
        origin: origin.to_string(),
        field: "terrain.grid.path".to_string(),
        file: file.to_path_buf(),
        reason,
    };
    let f = std::fs::File::open(file).map_err(|e| fail(format!("cannot open: {e}")))?;
    let decoder = png::Decoder::new(std::io::BufReader::new(f));
    let mut reader = decoder
        .read_info()
        .map_err(|e| fail(format!("not a PNG: {e}")))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| fail("image too large".to_string()))?;
    let mut buf = vec![0u8; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| fail(format!("cannot decode: {e}")))?;
    if info.color_type != png::ColorType::Grayscale {
        return Err(fail(format!(
            "colour type {:?}; allowed: grayscale (8 or 16 bit)",
            info.color_type
        )));
    }
    let (nx, ny) = (info.width as usize, info.height as usize);
    if nx * ny > crate::compile::MAX_SAMPLES {
        return Err(fail(format!(
            "{nx} x {ny} pixels; allowed: at most {} samples",
            crate::compile::MAX_SAMPLES
        )));
    }
    let mut values = vec![0u16; nx * ny];
    for row in 0..ny {
        let j = ny - 1 - row;
        for i in 0..nx {
            values[j * nx + i] = match info.bit_depth {
                png::BitDepth::Sixteen => {
                    let k = (row * nx + i) * 2;
                    u16::from_be_bytes([buf[k], buf[k + 1]])
                }
                png::BitDepth::Eight => buf[row * nx + i] as u16,
                other => {
                    return Err(fail(format!("bit depth {other:?}; allowed: 8 or 16")));
                }
            };
        }
    }
    Ok((nx, ny, values))
}

/// Write a 16-bit grayscale PNG in the layout [`read`] expects.
pub fn write(file: &Path, nx: usize, ny: usize, values: &[u16]) -> std::io::Result<()> {
    let f = std::io::BufWriter::new(std::fs::File::create(file)?);
    let mut enc = png::Encoder::new(f, nx as u32, ny as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut w = enc.write_header().map_err(std::io::Error::other)?;
    let mut data = Vec::with_capacity(nx * ny * 2);
    for row in 0..ny {
        let j = ny - 1 - row;
        for i in 0..nx {
            data.extend_from_slice(&values[j * nx + i].to_be_bytes());
        }
    }
    w.write_image_data(&data).map_err(std::io::Error::other)
}
