//! The bytes a glTF file refers to: its buffers (the GLB chunk, `data:` URIs, files beside it)
//! and its encoded images. URIs are resolved relative to the glTF file; only regular files
//! inside the allowed folders ([`Folders`]) are read, never more bytes than a buffer declares;
//! images are checked against the size limits from their header before they are decoded.

use super::limits;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Files of at least this many bytes are mapped into memory rather than read
/// ([`Bytes::Mapped`]).
pub const MAP_FROM: u64 = 64 << 20;

/// The bytes of a file or a glTF buffer: owned, or a range of a file mapped into memory (files
/// of [`MAP_FROM`] bytes and more: a large GLB's binary chunk is read in place, with no copy
/// in fresh memory, which costs a 64 M-triangle scene's opening about 1.5 GB of page faults).
pub enum Bytes {
    Owned(Vec<u8>),
    Mapped(memmap2::Mmap, std::ops::Range<usize>),
}

impl std::ops::Deref for Bytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            Bytes::Owned(v) => v,
            Bytes::Mapped(m, r) => &m[r.clone()],
        }
    }
}

impl Bytes {
    /// The bytes of `path`, a regular file: mapped from [`MAP_FROM`] bytes on, else read.
    pub fn of_file(path: &Path) -> std::io::Result<Self> {
        Self::of_file_mapped_from(path, MAP_FROM)
    }

    /// [`Bytes::of_file`] mapping files of `map_from` bytes and more.
    pub(super) fn of_file_mapped_from(path: &Path, map_from: u64) -> std::io::Result<Self> {
        let file = std::fs::File::open(path)?;
        let size = file.metadata()?.len();
        if size >= map_from
            && let Ok(map) = crate::cl::kernels::map_file(&file)
        {
            let len = map.len();
            return Ok(Bytes::Mapped(map, 0..len));
        }
        drop(file);
        // A file that cannot be mapped is read: say how large it is when that fails too.
        std::fs::read(path).map(Bytes::Owned).map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!(
                    "cannot hold its {size} bytes ({:.1} GiB) in memory: {e}",
                    size as f64 / (1u64 << 30) as f64
                ),
            )
        })
    }

    /// The bytes of `range` (within these) alone; owned ones are moved down in place.
    pub fn into_range(self, range: std::ops::Range<usize>) -> Self {
        match self {
            Bytes::Owned(mut v) => {
                v.truncate(range.end);
                v.drain(..range.start);
                Bytes::Owned(v)
            }
            Bytes::Mapped(m, r) => Bytes::Mapped(m, r.start + range.start..r.start + range.end),
        }
    }

    /// The first `len` bytes alone.
    pub fn truncate(&mut self, len: usize) {
        match self {
            Bytes::Owned(v) => v.truncate(len),
            Bytes::Mapped(_, r) => r.end = r.end.min(r.start + len),
        }
    }
}

/// Where a glTF file's URIs may lead: they are relative to `base`, and a file is read only when
/// its real path (percent-decoding, `..` and symbolic links resolved) lies inside one of
/// `allowed`, so that `../../etc/passwd` or a link out of the folder is refused.
pub struct Folders {
    base: PathBuf,
    allowed: Vec<PathBuf>,
}

impl Folders {
    /// URIs relative to `base` (the glTF file's folder; empty means the current folder), files
    /// inside `base` or, when given, inside `asset_root`.
    pub fn new(base: &Path, asset_root: Option<&Path>) -> Result<Self, String> {
        let base = if base.as_os_str().is_empty() {
            Path::new(".")
        } else {
            base
        };
        let real = |dir: &Path| {
            dir.canonicalize()
                .map_err(|e| format!("{}: cannot resolve the folder: {e}", dir.display()))
        };
        let mut allowed = vec![real(base)?];
        if let Some(root) = asset_root {
            allowed.push(real(root)?);
        }
        Ok(Folders {
            base: base.to_path_buf(),
            allowed,
        })
    }

    /// The real path of `relative` (from the base), or why it may not be read.
    fn file(&self, uri: &str, relative: &Path) -> Result<PathBuf, String> {
        let real = self
            .base
            .join(relative)
            .canonicalize()
            .map_err(|e| format!("'{uri}': {e}"))?;
        if !self.allowed.iter().any(|dir| real.starts_with(dir)) {
            return Err(format!(
                "'{uri}' resolves outside the scene's folder (--asset-root DIR allows a wider one)"
            ));
        }
        Ok(real)
    }
}

/// Loads every buffer of `document`: exactly `byteLength` bytes each.
pub fn load_buffers(
    document: &gltf::Document,
    base: Option<&Folders>,
    blob: Option<Bytes>,
) -> Result<Vec<Bytes>, String> {
    let mut blob = blob;
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let length = buffer.length();
        if super::compression::is_meshopt_fallback(document.as_json(), i) {
            // A meshopt fallback buffer: no bytes in the file; its views are decoded from
            // compressed data instead, never allocated from byteLength here.
            out.push(Bytes::Owned(Vec::new()));
            continue;
        }
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| format!("buffers[{i}]: no uri and no GLB binary chunk"))?,
            gltf::buffer::Source::Uri(uri) => {
                match resolve(uri, base).map_err(|e| format!("buffers[{i}].uri: {e}"))? {
                    Resolved::Data(bytes) => Bytes::Owned(bytes),
                    Resolved::File(path) => read_buffer_file(&path, length)
                        .map_err(|e| format!("buffers[{i}].uri: {}: {e}", path.display()))?,
                }
            }
        };
        if data.len() < length {
            return Err(format!(
                "buffers[{i}]: byteLength is {length} but only {} bytes exist",
                data.len()
            ));
        }
        data.truncate(length);
        out.push(data);
    }
    Ok(out)
}

/// Where a URI points.
enum Resolved {
    /// The decoded bytes of a `data:` URI.
    Data(Vec<u8>),
    /// The real path of a file inside the allowed folders.
    File(PathBuf),
}

/// Resolves a glTF URI: a base64 `data:` URI, or a relative path (percent-encoded) from
/// `base` that stays inside its allowed folders. Other schemes and absolute paths are refused.
fn resolve(uri: &str, base: Option<&Folders>) -> Result<Resolved, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err("only base64 data: URIs are supported".into());
        };
        return base64::decode(payload)
            .map(Resolved::Data)
            .map_err(|e| format!("bad base64 data: {e}"));
    }
    let scheme = uri
        .split_once(':')
        .is_some_and(|(s, _)| !s.is_empty() && !s.contains('/'));
    if scheme {
        return Err(format!(
            "'{uri}': only relative paths and data: URIs are supported"
        ));
    }
    let decoded = percent_encoding::percent_decode_str(uri)
        .decode_utf8()
        .map_err(|_| format!("'{uri}' is not valid UTF-8 once percent-decoded"))?;
    let relative = Path::new(decoded.as_ref());
    if relative.is_absolute() || decoded.starts_with('/') || decoded.starts_with('\\') {
        return Err(format!("'{uri}' must be relative to the glTF file"));
    }
    let Some(base) = base else {
        return Err(format!(
            "'{uri}' names a file, but the glTF was not loaded from a folder"
        ));
    };
    base.file(uri, relative).map(Resolved::File)
}

/// An external buffer file of at least `want` bytes: mapped from [`MAP_FROM`] bytes on (as a
/// GLB file is), else read (no more than `want` bytes).
fn read_buffer_file(path: &Path, want: usize) -> Result<Bytes, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if meta.is_file() && meta.len() >= MAP_FROM && meta.len() >= want as u64 {
        return Bytes::of_file(path).map_err(|e| e.to_string());
    }
    read_regular(path, Some(want)).map(Bytes::Owned)
}

/// Reads a regular file: exactly `want` bytes from its start when given (an error when it is
/// shorter), else the whole file up to [`limits::MAX_IMAGE_DECODE_BYTES`]. Devices, pipes and
/// folders are refused before anything is read, so `/dev/zero` cannot fill memory.
fn read_regular(path: &Path, want: Option<usize>) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    let size = meta.len();
    let want = match want {
        Some(w) if (w as u64) > size => {
            return Err(format!("{size} bytes, but {w} are declared"));
        }
        Some(w) => w as u64,
        None if size > limits::MAX_IMAGE_DECODE_BYTES => {
            return Err(format!(
                "{size} bytes is more than the limit of {}",
                limits::MAX_IMAGE_DECODE_BYTES
            ));
        }
        None => size,
    };
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut data = Vec::with_capacity(want as usize);
    file.take(want)
        .read_to_end(&mut data)
        .map_err(|e| e.to_string())?;
    if (data.len() as u64) < want {
        return Err(format!("{} bytes, but {want} are declared", data.len()));
    }
    Ok(data)
}

/// The pixels all images of one scene may decode to together
/// ([`limits::MAX_DECODED_PIXELS`]): each image takes its share from its header before it is
/// decoded, so that many images each under the per-image limit cannot exhaust memory together.
pub struct DecodeBudget(std::sync::atomic::AtomicU64);

impl Default for DecodeBudget {
    fn default() -> Self {
        DecodeBudget(std::sync::atomic::AtomicU64::new(
            limits::MAX_DECODED_PIXELS,
        ))
    }
}

impl DecodeBudget {
    /// Takes `width × height` pixels, or says that the budget is spent.
    fn take(&self, width: u32, height: u32) -> Result<(), String> {
        use std::sync::atomic::Ordering;
        let pixels = width as u64 * height as u64;
        self.0
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |left| {
                left.checked_sub(pixels)
            })
            .map(|_| ())
            .map_err(|_| {
                format!(
                    "its {width}×{height} pixels would take the scene's images past {} pixels \
                     in all",
                    limits::MAX_DECODED_PIXELS
                )
            })
    }
}

/// Reads and decodes image `image` of the document (`images[i]`) with its size checked from
/// the header first, against the per-image limits and what is left of `budget`; `base`
/// resolves relative URIs.
pub fn decode_image(
    image: &gltf::Image,
    base: Option<&Folders>,
    buffers: &[Bytes],
    budget: &DecodeBudget,
) -> Result<gltf::image::Data, String> {
    let bytes: std::borrow::Cow<[u8]> = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let start = view.offset();
            let slice = buffers
                .get(view.buffer().index())
                .and_then(|b| b.get(start..start.checked_add(view.length())?))
                .ok_or_else(|| {
                    format!(
                        "bufferViews[{}] lies outside buffers[{}]",
                        view.index(),
                        view.buffer().index()
                    )
                })?;
            slice.into()
        }
        gltf::image::Source::Uri { uri, .. } => match resolve(uri, base)? {
            Resolved::Data(bytes) => bytes.into(),
            Resolved::File(path) => read_regular(&path, None)
                .map_err(|e| format!("{}: {e}", path.display()))?
                .into(),
        },
    };
    decode_bounded(&bytes, budget)
}

/// Decodes an encoded PNG, JPEG, WebP or KTX2 (Basis Universal) image after checking its
/// header's size against the limits and taking its pixels from `budget`.
fn decode_bounded(bytes: &[u8], budget: &DecodeBudget) -> Result<gltf::image::Data, String> {
    use gltf::image::Format as F;
    use image::DynamicImage as D;
    if super::basisu::is_ktx2(bytes) {
        // The KTX2 decoder checks its header against the per-image limits itself.
        let data = super::basisu::decode(bytes)?;
        budget.take(data.width, data.height)?;
        return Ok(data);
    }
    let format = image::guess_format(bytes).map_err(|e| e.to_string())?;
    let reader = || image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let (width, height) = reader().into_dimensions().map_err(|e| e.to_string())?;
    limits::check_image_size(width, height)?;
    budget.take(width, height)?;
    let mut bounded = reader();
    let mut caps = image::Limits::default();
    caps.max_image_width = Some(limits::MAX_IMAGE_SIDE);
    caps.max_image_height = Some(limits::MAX_IMAGE_SIDE);
    caps.max_alloc = Some(limits::MAX_IMAGE_DECODE_BYTES);
    bounded.limits(caps);
    let decoded = bounded.decode().map_err(|e| e.to_string())?;
    let format = match &decoded {
        D::ImageLuma8(_) => F::R8,
        D::ImageLumaA8(_) => F::R8G8,
        D::ImageRgb8(_) => F::R8G8B8,
        D::ImageRgba8(_) => F::R8G8B8A8,
        D::ImageLuma16(_) => F::R16,
        D::ImageLumaA16(_) => F::R16G16,
        D::ImageRgb16(_) => F::R16G16B16,
        D::ImageRgba16(_) => F::R16G16B16A16,
        D::ImageRgb32F(_) => F::R32G32B32FLOAT,
        D::ImageRgba32F(_) => F::R32G32B32A32FLOAT,
        other => return Err(format!("pixel format {:?} is not supported", other.color())),
    };
    Ok(gltf::image::Data {
        width: decoded.width(),
        height: decoded.height(),
        pixels: decoded.into_bytes(),
        format,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Images take their pixels from one budget before they are decoded: past it, an image
    /// is refused from its header, whatever the per-image limits allow.
    #[test]
    fn images_together_stay_within_the_decode_budget() {
        let mut png = Vec::new();
        image::RgbaImage::new(64, 32)
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let budget = DecodeBudget(std::sync::atomic::AtomicU64::new(3 * 64 * 32));
        for _ in 0..3 {
            let data = decode_bounded(&png, &budget).unwrap();
            assert_eq!((data.width, data.height), (64, 32));
        }
        let e = decode_bounded(&png, &budget).unwrap_err();
        assert!(e.contains("64×32") && e.contains("in all"), "{e}");
        // A refused image takes nothing: a smaller one still fits.
        let budget = DecodeBudget(std::sync::atomic::AtomicU64::new(64 * 32 - 1));
        assert!(decode_bounded(&png, &budget).is_err());
        assert_eq!(
            budget.0.load(std::sync::atomic::Ordering::Relaxed),
            64 * 32 - 1
        );
        assert_eq!(
            DecodeBudget::default().0.into_inner(),
            limits::MAX_DECODED_PIXELS
        );
    }

    /// A mapped file gives the bytes a read gives, and its ranges those of the read bytes.
    #[test]
    fn a_mapped_file_reads_as_its_bytes() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
        let read = std::fs::read(&path).unwrap();
        let mapped = Bytes::of_file_mapped_from(&path, 0).unwrap();
        assert!(matches!(mapped, Bytes::Mapped(..)));
        assert_eq!(&mapped[..], &read[..]);
        let mut part = mapped.into_range(12..100);
        assert_eq!(&part[..], &read[12..100]);
        part.truncate(10);
        assert_eq!(&part[..], &read[12..22]);
        let owned = Bytes::Owned(read.clone()).into_range(12..100);
        assert!(matches!(owned, Bytes::Owned(_)));
        assert_eq!(&owned[..], &read[12..100]);
    }
}
