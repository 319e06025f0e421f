//! `KHR_texture_basisu`: KTX2 images holding Basis Universal data (ETC1S with BasisLZ
//! supercompression, or UASTC, raw or Zstandard-supercompressed), transcoded to RGBA8 on the
//! host.
//!
//! The `ktx2` crate reads the container (header, level index, data format descriptor,
//! supercompression global data); `ruzstd` undoes Zstandard; Binomial's own transcoder (the
//! `basis-universal` crate) decodes the texels. That crate wraps the `.basis` transcoder and
//! the low-level UASTC one but not the KTX2 transcoder, so ETC1S levels are handed to it as the
//! one-image `.basis` file holding the same codebooks, Huffman tables and slices (BasisLZ is the
//! `.basis` ETC1S payload in another container), and UASTC levels go to the low-level UASTC
//! transcoder directly.
//!
//! Only level 0 of the first layer and face is read (the renderer builds its own mip chain).
//! Every size is checked before it is allocated: the header's dimensions against the image
//! limits, the level and its slices against the bytes that exist, the Zstandard output against
//! the size UASTC needs.

use super::limits::check_image_size;
use basis_universal::{TranscodeParameters, Transcoder, TranscoderTextureFormat};
use ktx2::{ColorModel, SupercompressionScheme};
use std::io::Read;

/// The 12 bytes every KTX2 file starts with.
const MAGIC: [u8; 12] = [
    0xAB, b'K', b'T', b'X', b' ', b'2', b'0', 0xBB, b'\r', b'\n', 0x1A, b'\n',
];

/// Bytes of one UASTC block (4×4 texels).
const UASTC_BLOCK_BYTES: u64 = 16;

/// Whether `bytes` is a KTX2 file (by its identifier).
pub fn is_ktx2(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// Transcodes a KTX2 Basis Universal image to RGBA8 (`gltf::image::Data`, 4 bytes a texel).
pub fn decode(bytes: &[u8]) -> Result<gltf::image::Data, String> {
    check_dfd_dimensions(bytes)?;
    let reader = ktx2::Reader::new(bytes).map_err(|e| format!("not a valid KTX2 file: {e}"))?;
    let header = reader.header();
    let (width, height) = (header.pixel_width, header.pixel_height);
    check_image_size(width, height)?;
    if header.pixel_depth > 1 || header.face_count != 1 {
        return Err(format!(
            "KTX2 image is not 2D (depth {}, {} faces)",
            header.pixel_depth, header.face_count
        ));
    }
    if let Some(format) = header.format {
        return Err(format!(
            "KTX2 vkFormat {format:?} is not Basis Universal (KHR_texture_basisu needs \
             VK_FORMAT_UNDEFINED with ETC1S or UASTC data)"
        ));
    }
    let Some(level) = reader.levels().next() else {
        return Err("KTX2 file has no levels".into());
    };
    let model = reader.basic_dfd().and_then(|d| d.color_model);
    let scheme = header.supercompression_scheme;
    let rgba = match (model, scheme) {
        (Some(ColorModel::ETC1S), Some(SupercompressionScheme::BasisLZ)) => {
            let images =
                u64::from(header.layer_count.max(1)) * u64::from(header.level_count.max(1));
            let (codebooks, slices) =
                etc1s_slices(reader.supercompression_global_data(), level.data, images)?;
            transcode_basis(&basis_file(Some(&codebooks), &slices, width, height)?)?
        }
        (Some(ColorModel::UASTC), None | Some(SupercompressionScheme::Zstandard)) => {
            let blocks = u64::from(width.div_ceil(4)) * u64::from(height.div_ceil(4));
            let want = blocks * UASTC_BLOCK_BYTES;
            let data: std::borrow::Cow<[u8]> = match scheme {
                Some(_) => unzstd(level.data, want)?.into(),
                None => level.data.into(),
            };
            // The first layer's level 0: the level holds every layer one after the other.
            let Some(data) = data.get(..want as usize) else {
                return Err(format!(
                    "KTX2 level 0 holds {} bytes of UASTC, {width}×{height} needs {want}",
                    data.len()
                ));
            };
            let has_alpha = reader.basic_dfd().is_some_and(|d| {
                d.sample_information
                    .first()
                    .is_some_and(|s| matches!(s.channel_type, UASTC_RGBA | UASTC_RRRG))
            });
            transcode_basis(&basis_file(None, &[(data, has_alpha)], width, height)?)?
        }
        (Some(ColorModel::ETC1S), other) | (Some(ColorModel::UASTC), other) => {
            return Err(format!(
                "KTX2 {} data with supercompression {} (ETC1S needs BasisLZ, UASTC none or \
                 Zstandard)",
                if model == Some(ColorModel::ETC1S) {
                    "ETC1S"
                } else {
                    "UASTC"
                },
                other.map_or_else(|| "none".to_string(), |s| format!("{s:?}"))
            ));
        }
        (other, _) => {
            return Err(format!(
                "KTX2 color model {} is not Basis Universal (ETC1S or UASTC)",
                other.map_or_else(|| "unknown".to_string(), |m| format!("{m:?}"))
            ));
        }
    };
    if rgba.len() as u64 != u64::from(width) * u64::from(height) * 4 {
        return Err("the transcoder returned the wrong number of texels".into());
    }
    Ok(gltf::image::Data {
        pixels: rgba,
        format: gltf::image::Format::R8G8B8A8,
        width,
        height,
    })
}

/// UASTC channel ids of the first DFD sample that carry alpha (KHR_DF_CHANNEL_UASTC_RGBA and
/// _RRRG).
const UASTC_RGBA: u8 = 3;
const UASTC_RRRG: u8 = 5;

/// Refuses a data format descriptor that the `ktx2` crate (0.5) would panic on: a basic block
/// whose texel block dimension byte is 255 (it adds one in a `u8`). Anything else malformed is
/// left for the crate to report.
fn check_dfd_dimensions(bytes: &[u8]) -> Result<(), String> {
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(
            bytes.get(at..at.checked_add(4)?)?.try_into().ok()?,
        ))
    };
    let (Some(offset), Some(length)) = (u32_at(48), u32_at(52)) else {
        return Ok(());
    };
    let (offset, length) = (offset as usize, length as usize);
    let end = offset.saturating_add(length).min(bytes.len());
    let mut at = offset.saturating_add(4);
    while at.saturating_add(8) <= end {
        let Some(word) = u32_at(at) else { break };
        let size = bytes
            .get(at + 6..at + 8)
            .map_or(0, |b| u16::from_le_bytes([b[0], b[1]]) as usize);
        let (vendor, kind) = (word & 0x1_FFFF, word >> 17);
        if vendor == 0
            && kind == 0
            && bytes
                .get(at + 12..at + 16)
                .is_some_and(|dims| dims.contains(&255))
        {
            return Err("not a valid KTX2 file: texel block dimension of 256".into());
        }
        if size == 0 {
            break;
        }
        at = at.saturating_add(size);
    }
    Ok(())
}

/// Undoes Zstandard supercompression, reading at most `want` bytes (and failing unless
/// exactly `want` come out).
fn unzstd(data: &[u8], want: u64) -> Result<Vec<u8>, String> {
    let window = want.next_power_of_two().max(1 << 20);
    let decoder = ruzstd::decoding::StreamingDecoder::new_with_max_window_size(data, window)
        .map_err(|e| format!("the Zstandard data does not decode: {e}"))?;
    // Grown as the data decodes (a header may claim a large image over a few bytes).
    let mut out = Vec::new();
    decoder
        .take(want + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("the Zstandard data does not decode: {e}"))?;
    match (out.len() as u64).cmp(&want) {
        std::cmp::Ordering::Equal => {}
        std::cmp::Ordering::Less => {
            return Err(format!(
                "the Zstandard data decodes to {} bytes, UASTC needs {want}",
                out.len()
            ));
        }
        std::cmp::Ordering::Greater => {
            return Err(format!(
                "the Zstandard data decodes to more than the {want} bytes UASTC needs"
            ));
        }
    }
    Ok(out)
}

/// Little-endian reader over the supercompression global data.
struct Fields<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Fields<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let out = self
            .bytes
            .get(self.at..self.at.saturating_add(n))
            .ok_or("the BasisLZ global data is truncated")?;
        self.at += n;
        Ok(out)
    }
    fn u16(&mut self) -> Result<u16, String> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    fn u32(&mut self) -> Result<u32, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

/// `.basis` header size (`basist::basis_file_header`, packed).
const BASIS_HEADER_BYTES: usize = 77;
/// `.basis` slice descriptor size (`basist::basis_slice_desc`, packed).
const BASIS_SLICE_BYTES: usize = 23;

/// ETC1S codebooks and Huffman tables (from the BasisLZ global data).
struct Codebooks<'a> {
    endpoint_count: u16,
    selector_count: u16,
    endpoints: &'a [u8],
    selectors: &'a [u8],
    tables: &'a [u8],
}

/// A `.basis` slice: its bytes, and whether it holds alpha (an ETC1S alpha slice, or UASTC
/// with alpha).
type Slice<'a> = (&'a [u8], bool);

/// Reads the BasisLZ global data of a KTX2 file: the codebooks, and the RGB (and alpha) slice
/// of the first image of level 0 from `level`. `images` is the number of image descriptors the
/// global data holds (levels × layers). Offsets and lengths are checked against the bytes that
/// exist.
fn etc1s_slices<'a>(
    sgd: &'a [u8],
    level: &'a [u8],
    images: u64,
) -> Result<(Codebooks<'a>, Vec<Slice<'a>>), String> {
    let mut f = Fields { bytes: sgd, at: 0 };
    let endpoint_count = f.u16()?;
    let selector_count = f.u16()?;
    let endpoints_len = f.u32()? as usize;
    let selectors_len = f.u32()? as usize;
    let tables_len = f.u32()? as usize;
    let extended_len = f.u32()? as usize;
    // Image descriptors: level 0's first image comes first.
    let descs_len = images
        .checked_mul(20)
        .filter(|&n| n <= sgd.len() as u64)
        .ok_or("the BasisLZ global data is truncated")? as usize;
    let mut descs = Fields {
        bytes: f.take(descs_len)?,
        at: 0,
    };
    let _flags = descs.u32()?;
    let rgb = (descs.u32()? as usize, descs.u32()? as usize);
    let alpha = (descs.u32()? as usize, descs.u32()? as usize);
    let codebooks = Codebooks {
        endpoint_count,
        selector_count,
        endpoints: f.take(endpoints_len)?,
        selectors: f.take(selectors_len)?,
        tables: f.take(tables_len)?,
    };
    f.take(extended_len)?;
    if endpoint_count == 0 || selector_count == 0 {
        return Err("the BasisLZ codebooks are empty".into());
    }
    let slice = |(offset, length): (usize, usize), what: &str| {
        level
            .get(offset..offset.saturating_add(length))
            .filter(|s| !s.is_empty())
            .ok_or_else(|| format!("the BasisLZ {what} slice lies outside level 0"))
    };
    let mut slices = vec![(slice(rgb, "RGB")?, false)];
    if alpha.1 != 0 {
        slices.push((slice(alpha, "alpha")?, true));
    }
    Ok((codebooks, slices))
}

/// The one-image, one-level `.basis` file holding `slices` of a `width` × `height` image:
/// ETC1S with `codebooks` (an RGB slice, then an optional alpha slice), else one UASTC slice.
fn basis_file(
    codebooks: Option<&Codebooks>,
    slices: &[Slice],
    width: u32,
    height: u32,
) -> Result<Vec<u8>, String> {
    let (endpoints, selectors, tables) = codebooks.map_or((&[][..], &[][..], &[][..]), |c| {
        (c.endpoints, c.selectors, c.tables)
    });
    let descs_end = BASIS_HEADER_BYTES + slices.len() * BASIS_SLICE_BYTES;
    let mut data_at = descs_end + endpoints.len() + selectors.len() + tables.len();
    let total = data_at + slices.iter().map(|s| s.0.len()).sum::<usize>();
    let total32 = u32::try_from(total).map_err(|_| "the Basis Universal data is too large")?;
    let put = |out: &mut Vec<u8>, value: u64, bytes: usize| {
        out.extend_from_slice(&value.to_le_bytes()[..bytes]);
    };
    let alpha = slices.iter().any(|s| s.1);
    let mut out = Vec::with_capacity(total);
    put(&mut out, u64::from(u16::from_be_bytes(*b"Bs")), 2); // m_sig
    put(&mut out, 0x13, 2); // m_ver
    put(&mut out, BASIS_HEADER_BYTES as u64, 2); // m_header_size
    put(&mut out, 0, 2); // m_header_crc16 (checked only by validate_file_checksums)
    put(&mut out, u64::from(total32) - BASIS_HEADER_BYTES as u64, 4); // m_data_size
    put(&mut out, 0, 2); // m_data_crc16
    put(&mut out, slices.len() as u64, 3); // m_total_slices
    put(&mut out, 1, 3); // m_total_images
    put(&mut out, u64::from(codebooks.is_none()), 1); // m_tex_format: 0 ETC1S, 1 UASTC 4×4
    // m_flags: cBASISHeaderFlagETC1S, cBASISHeaderFlagHasAlphaSlices
    put(
        &mut out,
        u64::from(codebooks.is_some()) | if alpha { 4 } else { 0 },
        2,
    );
    put(&mut out, 0, 1); // m_tex_type: 2D
    put(&mut out, 0, 3); // m_us_per_frame
    put(&mut out, 0, 4); // m_reserved
    put(&mut out, 0, 8); // m_userdata0, m_userdata1
    let mut at = descs_end as u64;
    let (endpoint_count, selector_count) =
        codebooks.map_or((0, 0), |c| (c.endpoint_count, c.selector_count));
    // m_total_endpoints, m_endpoint_cb_file_ofs/size, then the same for the selectors.
    for (count, part) in [(endpoint_count, endpoints), (selector_count, selectors)] {
        put(&mut out, count.into(), 2);
        put(&mut out, at, 4);
        put(&mut out, part.len() as u64, 3);
        at += part.len() as u64;
    }
    put(&mut out, at, 4); // m_tables_file_ofs
    put(&mut out, tables.len() as u64, 4);
    put(&mut out, BASIS_HEADER_BYTES as u64, 4); // m_slice_desc_file_ofs
    put(&mut out, 0, 8); // m_extended_file_ofs, m_extended_file_size
    debug_assert_eq!(out.len(), BASIS_HEADER_BYTES);
    for &(data, has_alpha) in slices {
        put(&mut out, 0, 3); // m_image_index
        put(&mut out, 0, 1); // m_level_index
        put(&mut out, u64::from(has_alpha), 1); // m_flags: cSliceDescFlagsHasAlpha
        put(&mut out, u64::from(width), 2);
        put(&mut out, u64::from(height), 2);
        put(&mut out, u64::from(width.div_ceil(4)), 2);
        put(&mut out, u64::from(height.div_ceil(4)), 2);
        put(&mut out, data_at as u64, 4);
        put(&mut out, data.len() as u64, 4);
        put(&mut out, 0, 2); // m_slice_data_crc16
        data_at += data.len();
    }
    for part in [endpoints, selectors, tables] {
        out.extend_from_slice(part);
    }
    for (data, _) in slices {
        out.extend_from_slice(data);
    }
    debug_assert_eq!(out.len(), total);
    Ok(out)
}

/// Transcodes image 0, level 0 of a `.basis` file to RGBA8.
fn transcode_basis(basis: &[u8]) -> Result<Vec<u8>, String> {
    basis_universal::transcoder_init();
    let mut transcoder = Transcoder::new();
    transcoder
        .prepare_transcoding(basis)
        .map_err(|()| "the Basis Universal codebooks do not decode".to_string())?;
    transcoder
        .transcode_image_level(
            basis,
            TranscoderTextureFormat::RGBA32,
            TranscodeParameters::default(),
        )
        .map_err(|e| format!("the Basis Universal data does not transcode ({e:?})"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fixtures scripts/ktx2_fixtures.sh made with Binomial's encoder.
    fn fixture(name: &str) -> Vec<u8> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/ktx2")
            .join(name);
        std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    fn png(name: &str) -> image::RgbaImage {
        image::load_from_memory(&fixture(name)).unwrap().to_rgba8()
    }

    /// One fixture of each kind: ETC1S with and without alpha, UASTC with Zstandard and raw.
    const BASIS_FIXTURES: [&str; 4] = [
        "etc1s.ktx2",
        "etc1s-alpha.ktx2",
        "uastc.ktx2",
        "uastc-alpha.ktx2",
    ];

    /// Mean absolute difference per channel (R, G, B, A) between a transcode and a PNG.
    fn difference(data: &gltf::image::Data, reference: &image::RgbaImage) -> [f64; 4] {
        assert_eq!((data.width, data.height), reference.dimensions());
        assert_eq!(data.format, gltf::image::Format::R8G8B8A8);
        let mut sum = [0.0; 4];
        for (got, want) in data.pixels.chunks_exact(4).zip(reference.pixels()) {
            for c in 0..4 {
                sum[c] += (f64::from(got[c]) - f64::from(want.0[c])).abs();
            }
        }
        sum.map(|s| s / f64::from(data.width * data.height))
    }

    #[test]
    fn etc1s_matches_basisu_own_decode_exactly() {
        let data = decode(&fixture("etc1s.ktx2")).unwrap();
        let reference = png("etc1s-etc1.png");
        let d = difference(&data, &reference);
        assert_eq!(&d[..3], &[0.0; 3], "RGB differs from basisu -unpack");
        assert!(data.pixels.chunks_exact(4).all(|p| p[3] == 255));
    }

    #[test]
    fn every_fixture_transcodes_close_to_its_source() {
        // (file, source, largest mean error of RGB, of alpha) in 8-bit steps. The 30×22
        // plasma is noise at block scale, the worst case for 4×4 block codecs: basisu's own
        // decodes (-unpack) err by 12.0 (ETC1S through ETC1) and 4.7 (UASTC through BC7).
        for (file, source, color, alpha) in [
            ("etc1s.ktx2", "rgb.png", 13.5, 0.0),
            ("etc1s-mips.ktx2", "rgb.png", 13.5, 0.0),
            ("etc1s-alpha.ktx2", "rgba.png", 13.5, 2.0),
            ("uastc.ktx2", "rgb.png", 5.5, 0.0),
            ("uastc-alpha.ktx2", "rgba.png", 6.0, 5.5),
        ] {
            let data = decode(&fixture(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            let d = difference(&data, &png(source));
            let rgb = (d[0] + d[1] + d[2]) / 3.0;
            eprintln!("{file}: mean error RGB {rgb:.2}, alpha {:.2}", d[3]);
            assert!(rgb <= color && d[3] <= alpha, "{file}: {d:?}");
        }
    }

    #[test]
    fn truncated_files_are_errors() {
        for file in BASIS_FIXTURES {
            let bytes = fixture(file);
            for len in 0..bytes.len() {
                if let Ok(d) = decode(&bytes[..len]) {
                    panic!(
                        "{file} cut to {len} bytes decodes ({}×{})",
                        d.width, d.height
                    );
                }
            }
        }
    }

    /// Writes a little-endian u32 into a copy of `bytes`.
    fn patched(bytes: &[u8], at: usize, value: u32) -> Vec<u8> {
        let mut out = bytes.to_vec();
        out[at..at + 4].copy_from_slice(&value.to_le_bytes());
        out
    }

    #[test]
    fn huge_dimensions_are_refused_from_the_header() {
        let bytes = fixture("uastc.ktx2");
        for (at, value) in [(20, 100_000), (24, 100_000), (20, u32::MAX), (24, 0)] {
            let e = decode(&patched(&bytes, at, value)).unwrap_err();
            assert!(
                e.contains("limit") || e.contains("empty"),
                "header word {at} = {value}: {e}"
            );
        }
        // 16384 × 16384 passes the side limit but not the pixel limit.
        let square = patched(&patched(&bytes, 20, 16384), 24, 16384);
        assert!(decode(&square).unwrap_err().contains("limit"));
    }

    #[test]
    fn wrong_supercompression_and_formats_are_refused() {
        let etc1s = fixture("etc1s.ktx2");
        let uastc = fixture("uastc.ktx2");
        for (bytes, scheme, want) in [
            (&etc1s, 0, "ETC1S data with supercompression none"),
            (&etc1s, 2, "ETC1S data with supercompression Zstandard"),
            (&uastc, 1, "UASTC data with supercompression BasisLZ"),
            (&uastc, 3, "UASTC data with supercompression ZLIB"),
        ] {
            let e = decode(&patched(bytes, 44, scheme)).unwrap_err();
            assert!(e.contains(want), "scheme {scheme}: {e}");
        }
        // A vkFormat other than VK_FORMAT_UNDEFINED (R8G8B8A8_SRGB).
        let e = decode(&patched(&uastc, 12, 43)).unwrap_err();
        assert!(e.contains("not Basis Universal"), "{e}");
        // Uncompressed, not Zstandard (the raw UASTC file claims Zstandard).
        let e = decode(&patched(&fixture("uastc-alpha.ktx2"), 44, 2)).unwrap_err();
        assert!(e.contains("Zstandard"), "{e}");
    }

    #[test]
    fn a_texel_block_dimension_of_256_is_an_error_not_a_panic() {
        let mut bytes = fixture("etc1s.ktx2");
        let dfd = u32::from_le_bytes(bytes[48..52].try_into().unwrap()) as usize;
        // DFD: total size (4), block header (8), model..flags (4), texel block dimensions.
        bytes[dfd + 16] = 255;
        assert!(decode(&bytes).unwrap_err().contains("texel block"));
    }

    /// Single-byte changes anywhere (the transcoder's own input included) end in an image of
    /// the size the header states, or an error; never a crash. `PENUMBRA_BASISU_MUTATIONS`
    /// sets the number per fixture (default 2000).
    #[test]
    fn mutated_files_decode_or_fail_cleanly() {
        let mutations: usize = std::env::var("PENUMBRA_BASISU_MUTATIONS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(2000);
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for file in BASIS_FIXTURES {
            let bytes = fixture(file);
            for _ in 0..mutations {
                let mut b = bytes.clone();
                for _ in 0..1 + next() % 3 {
                    let i = (next() % b.len() as u64) as usize;
                    b[i] = next() as u8;
                }
                if let Ok(d) = decode(&b) {
                    assert_eq!(d.pixels.len(), (d.width * d.height * 4) as usize, "{file}");
                }
            }
        }
    }
}
