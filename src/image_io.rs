//! Writing and reading linear images: EXR is linear radiance (RGB float). Tone-mapped PNGs are
//! written by `render::tonemap`. Every image is encoded in memory and written by
//! [`write_file`], whose every write is checked (a full disk is an error, never a success).

use anyhow::{Context, Result, bail};
use std::io::{Seek, Write};
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

/// The output file of a command, opened (and so checked) before the work that fills it: its
/// extension is a known format, it is not a folder, its folder exists and it can be written.
/// An existing file keeps its bytes until [`OutputFile::write`]; a file this opening created is
/// removed again when it is dropped unwritten (the work failed).
pub struct OutputFile {
    path: PathBuf,
    file: Option<std::fs::File>,
    created: bool,
    /// The format its extension names.
    pub format: Format,
}

impl OutputFile {
    /// Opens `path` for writing without changing it; one line saying why not.
    pub fn open(path: &Path) -> Result<Self> {
        let shown = path.display();
        if path.is_dir() {
            bail!("{shown}: the output is a folder");
        }
        let format = Format::of(path)?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
            && !dir.is_dir()
        {
            bail!("{}: the output folder does not exist", dir.display());
        }
        let existed = path.exists();
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create(!existed)
            .open(path)
            .map_err(|e| anyhow::anyhow!("{shown}: cannot write: {}", os_message(&e)))?;
        Ok(OutputFile {
            path: path.to_path_buf(),
            file: Some(file),
            created: !existed,
            format,
        })
    }

    /// Replaces the file's bytes with `bytes`, every write checked.
    pub fn write(self, bytes: &[u8]) -> Result<()> {
        self.write_with(|out| out.write_all(bytes))
    }

    /// Replaces the file's bytes with what `fill` writes (buffered: it may write in small
    /// pieces and seek), every write checked: an image streamed from its pixels, with no copy
    /// of the whole file in memory.
    pub fn write_with(
        mut self,
        fill: impl FnOnce(&mut std::io::BufWriter<&mut std::fs::File>) -> std::io::Result<()>,
    ) -> Result<()> {
        let mut file = self.file.take().expect("written once");
        let result = replace_contents(&mut file, fill);
        if result.is_err() && self.created {
            let _ = std::fs::remove_file(&self.path);
        }
        result.map_err(|e| {
            anyhow::anyhow!("{}: cannot write: {}", self.path.display(), os_message(&e))
        })
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if self.file.is_some() && self.created {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// The OS's message for `e` without the `(os error N)` suffix Rust appends.
fn os_message(e: &std::io::Error) -> String {
    let text = e.to_string();
    match text.rfind(" (os error ") {
        Some(at) => text[..at].to_string(),
        None => text,
    }
}

/// Writes what `fill` writes from the start of `file`, cutting what was there, and (for a
/// regular file) waits until it is on disk: an error of any step is returned, so that a full
/// disk or device (`/dev/full`) is never reported as a success.
fn replace_contents(
    file: &mut std::fs::File,
    fill: impl FnOnce(&mut std::io::BufWriter<&mut std::fs::File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let regular = file.metadata()?.is_file();
    if regular {
        file.set_len(0)?;
        file.rewind()?;
    }
    let mut out = std::io::BufWriter::with_capacity(1 << 20, &mut *file);
    fill(&mut out)?;
    out.into_inner()
        .map_err(std::io::IntoInnerError::into_error)?;
    file.flush()?;
    if regular {
        file.sync_all()?;
    }
    Ok(())
}

/// Writes `bytes` to `path` (created or replaced), every write checked.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut file = std::fs::File::create(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {}", path.display(), os_message(&e)))?;
    replace_contents(&mut file, |out| out.write_all(bytes))
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {}", path.display(), os_message(&e)))
}

/// Writes linear RGB as a float EXR.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<()> {
    write_file(path, &encode_exr(width, height, rgb, None)?)
}

/// Linear RGB (premultiplied by `alpha` when given, an A channel then) encoded as a float EXR.
pub fn encode_exr(
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    alpha: Option<&[f32]>,
) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let w = width as usize;
    let mut bytes = std::io::Cursor::new(Vec::new());
    let size = (w, height as usize);
    match alpha {
        None => {
            let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = rgb[y * w + x];
                (p[0], p[1], p[2])
            });
            Image::from_encoded_channels(size, EXR_ENCODING, channels)
                .write()
                .to_buffered(&mut bytes)
        }
        Some(alpha) => {
            let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
                let p = rgb[y * w + x];
                (p[0], p[1], p[2], alpha[y * w + x])
            });
            Image::from_encoded_channels(size, EXR_ENCODING, channels)
                .write()
                .to_buffered(&mut bytes)
        }
    }
    .context("cannot encode EXR")?;
    Ok(bytes.into_inner())
}

/// Float channels by name, each one value per pixel, row by row from the top.
pub type Channels = Vec<(String, Vec<f32>)>;

/// Linear RGB (premultiplied by `alpha` when given) as `R`, `G`, `B` (and `A`) with more named
/// float channels beside them in the same part (`albedo.R`, `depth.Z`: the dotted names by which
/// Blender, Nuke and OIDN's tools group channels into layers), each one value per pixel, row by
/// row from the top.
pub fn encode_exr_channels(
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    alpha: Option<&[f32]>,
    extra: &Channels,
) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let channel = |name: &str, values: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(values));
    let plane = |c: usize| rgb.iter().map(|p| p[c]).collect::<Vec<f32>>();
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    list.push(channel("R", plane(0)));
    list.push(channel("G", plane(1)));
    list.push(channel("B", plane(2)));
    if let Some(alpha) = alpha {
        list.push(channel("A", alpha.to_vec()));
    }
    for (name, values) in extra {
        anyhow::ensure!(
            values.len() == rgb.len(),
            "channel {name} has the wrong size"
        );
        list.push(channel(name, values.clone()));
    }
    encode_exr_layer(width, height, LayerAttributes::default(), list)
}

/// One EXR part of `channels` (any sample type, sorted by name as the format wants) with
/// `attributes`, encoded in memory with [`EXR_ENCODING`].
pub(crate) fn encode_exr_layer(
    width: u32,
    height: u32,
    attributes: exr::meta::header::LayerAttributes,
    channels: exr::prelude::SmallVec<[exr::image::AnyChannel<exr::image::FlatSamples>; 4]>,
) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let layer = Layer::new(
        (width as usize, height as usize),
        attributes,
        EXR_ENCODING,
        AnyChannels::sort(channels),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .context("cannot encode EXR")?;
    Ok(bytes.into_inner())
}

/// Every float channel of an EXR file's first part by name, one value per pixel row by row
/// from the top, with the image's width and height.
pub fn read_exr_channels(path: &Path) -> Result<(u32, u32, Channels)> {
    let layer = read_exr_layer(path)?;
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    Ok((layer.size.0 as u32, layer.size.1 as u32, channels))
}

/// The exr crate's default encoding (RLE, 64-pixel tiles) with the tiles in increasing order:
/// its default order is "unspecified", and its parallel compression then writes the tiles in
/// whatever order the threads finish them, so one image gave files that differed from run to
/// run. In order, the same pixels always make the same bytes.
pub(crate) const EXR_ENCODING: exr::image::Encoding = exr::image::Encoding {
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
    write_file(path, &encode_exr(width, height, rgb, Some(alpha))?)
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

/// An EXR file's first layer with every channel (of any sample type) and every attribute.
pub fn read_exr_layer(
    path: &Path,
) -> Result<exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read EXR: {e}", path.display()))?;
    Ok(image.layer_data)
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
