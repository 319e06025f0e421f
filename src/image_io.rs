//! Writing and reading linear images: EXR is linear radiance (RGB float). Tone-mapped PNGs are
//! written by `render::tonemap`.

use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// Image formats penumbra writes, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// OpenEXR, linear.
    Exr,
    /// PNG, display-referred.
    Png,
}

impl Format {
    /// The format a path's extension names.
    pub fn of(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("exr") => Ok(Format::Exr),
            Some("png") => Ok(Format::Png),
            _ => bail!("{}: output must end in .exr or .png", path.display()),
        }
    }
}

/// Writes linear RGB as a float EXR.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<()> {
    use exr::prelude::*;
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = rgb[y * w + x];
        (p[0], p[1], p[2])
    });
    Image::from_encoded_channels((w, height as usize), EXR_ENCODING, channels)
        .write()
        .to_file(path)
        .with_context(|| format!("{}: cannot write EXR", path.display()))
}

/// The exr crate's default encoding (RLE, 64-pixel tiles) with the tiles in increasing order:
/// its default order is "unspecified", and its parallel compression then writes the tiles in
/// whatever order the threads finish them, so one image gave files that differed from run to
/// run. In order, the same pixels always make the same bytes.
const EXR_ENCODING: exr::image::Encoding = exr::image::Encoding {
    line_order: exr::meta::attribute::LineOrder::Increasing,
    ..exr::image::Encoding::FAST_LOSSLESS
};

/// Writes premultiplied linear RGB with `alpha` as a float RGBA EXR.
pub fn write_exr_rgba(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    alpha: &[f32],
) -> Result<()> {
    use exr::prelude::*;
    let w = width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let p = rgb[y * w + x];
        (p[0], p[1], p[2], alpha[y * w + x])
    });
    Image::from_encoded_channels((w, height as usize), EXR_ENCODING, channels)
        .write()
        .to_file(path)
        .with_context(|| format!("{}: cannot write EXR", path.display()))
}

/// The size of each layer of an EXR file and its chunk count, from the header alone (no pixel
/// is read): `(width, height, chunks)` per layer.
pub fn exr_layer_sizes(path: &Path) -> Result<Vec<(u64, u64, u64)>> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .with_context(|| format!("{}: cannot read EXR", path.display()))?;
    Ok(meta
        .headers
        .iter()
        .map(|h| {
            (
                h.layer_size.width() as u64,
                h.layer_size.height() as u64,
                h.chunk_count as u64,
            )
        })
        .collect())
}

/// Reads the RGB channels of an EXR file: (width, height, pixels).
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| {
            (
                resolution.width(),
                vec![[0f32; 3]; resolution.width() * resolution.height()],
            )
        },
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b];
        },
    )
    .with_context(|| format!("{}: cannot read EXR", path.display()))?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.width() as u32, size.height() as u32, pixels))
}

/// A path in `dir` named `{stem}-{timestamp}.{ext}` that does not exist yet; a counter is
/// appended when several are made in the same second. Never returns an existing file.
pub fn unique_path(dir: &Path, stem: &str, timestamp: &str, ext: &str) -> PathBuf {
    let mut candidate = dir.join(format!("{stem}-{timestamp}.{ext}"));
    let mut n = 2;
    while candidate.exists() {
        candidate = dir.join(format!("{stem}-{timestamp}-{n}.{ext}"));
        n += 1;
    }
    candidate
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trips_linear_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let px = vec![[0.25, 1.5, 100.0], [0.0, 0.001, 7.0]];
        write_exr(&path, 2, 1, &px).unwrap();
        let (w, h, back) = read_exr(&path).unwrap();
        assert_eq!((w, h), (2, 1));
        assert_eq!(back, px);
    }

    #[test]
    fn the_same_pixels_make_the_same_exr_bytes() {
        // Many tiles of noisy values, so that the parallel compression finishes them out of
        // order: the files must still be equal byte for byte, RGB and RGBA.
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (640u32, 448u32);
        let mut state = 1u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let px: Vec<[f32; 3]> = (0..w * h).map(|_| [next(), next(), next()]).collect();
        let alpha: Vec<f32> = (0..w * h).map(|_| next()).collect();
        let files: Vec<Vec<u8>> = (0..6)
            .map(|i| {
                let path = dir.path().join(format!("{i}.exr"));
                if i % 2 == 0 {
                    write_exr(&path, w, h, &px).unwrap();
                } else {
                    write_exr_rgba(&path, w, h, &px, &alpha).unwrap();
                }
                std::fs::read(path).unwrap()
            })
            .collect();
        for (i, f) in files.iter().enumerate().skip(2) {
            assert!(*f == files[i % 2], "file {i} differs from file {}", i % 2);
        }
        let (_, _, back) = read_exr(&dir.path().join("0.exr")).unwrap();
        assert_eq!(back, px);
    }

    #[test]
    fn unique_path_never_returns_an_existing_file() {
        let dir = tempfile::tempdir().unwrap();
        let a = unique_path(dir.path(), "shot", "t", "png");
        std::fs::write(&a, b"x").unwrap();
        let b = unique_path(dir.path(), "shot", "t", "png");
        assert_ne!(a, b);
        assert!(!b.exists());
    }

    #[test]
    fn format_follows_the_extension() {
        assert_eq!(Format::of(Path::new("a.EXR")).unwrap(), Format::Exr);
        assert_eq!(Format::of(Path::new("a.png")).unwrap(), Format::Png);
        assert!(Format::of(Path::new("a.jpg")).is_err());
    }
}
