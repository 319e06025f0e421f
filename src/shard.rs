//! Shards: an EXR holding a range of samples of the deterministic sequence, exactly, so that
//! `penumbra merge` adds shards up to the image one render of all their samples makes, bit for
//! bit (docs/farm.md).
//!
//! A shard EXR is one layer: `R`, `G`, `B` (and `A` with the background cut out), the image as
//! `render` writes it, and the film's exact integer sums (kernels/shared/film.h) as 32-bit
//! unsigned halves `film.R_hi`, `film.R_lo`, … `film.N_lo` (`N` the count). The header's
//! `penumbraShard` attribute is [`ShardInfo`] as JSON. Merging adds the integer sums, which is
//! associative, and makes the image from them with the same function `render` uses
//! ([`film::image_into`]): the RGB(A) of a merge equals that of one render of the same samples.

use crate::render::film::{self, FilmPixel};
use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The header attribute holding [`ShardInfo`].
const ATTRIBUTE: &str = "penumbraShard";

/// The film's channels: each lane's high and low 32 bits.
const FILM_CHANNELS: [(&str, &str); 4] = [
    ("film.R_hi", "film.R_lo"),
    ("film.G_hi", "film.G_lo"),
    ("film.B_hi", "film.B_lo"),
    ("film.N_hi", "film.N_lo"),
];

/// What a shard's header says about it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// The index of its first sample in the random sequence.
    pub sample_start: u32,
    /// Its samples per pixel: samples `sample_start` … `sample_start + samples − 1`.
    pub samples: u32,
    /// [`identity`] of the scene file and every setting that changes the linear image: shards
    /// merge only when it is the same.
    pub identity: String,
    /// The film counts only the samples whose camera ray hit (`--background` cut out): its
    /// mean is then over all `samples`.
    pub counted: bool,
    /// How the PNG of a merge shows it (`render`'s options): the background, the exposure in
    /// stops when it was fixed (`--exposure`, `--ev100` or metered on the lights; `None`:
    /// metered on the image) and the tone curve.
    pub background: String,
    /// See `background`.
    pub exposure: Option<f32>,
    /// See `background`.
    pub tonemap: String,
    /// The scene as given on the command line (for people; not compared).
    pub scene: String,
    /// The kernels and the device that rendered it: a merge equals one render bit for bit when
    /// they were the same for every shard ("mixed" after a merge of several).
    pub kernel: String,
    /// See `kernel`.
    pub device: String,
}

/// What a channel of a shard's EXR holds.
#[derive(Clone, Copy, Debug)]
enum Holds {
    /// The image's red, green or blue (f32).
    Image(usize),
    /// The coverage, the alpha of a cut-out background (f32).
    Coverage,
    /// The film's sums or count: lane `lane`'s bits from `shift` on, 32 of them (u32).
    Film { lane: usize, shift: u32 },
}

/// A shard: its size, header and film.
#[derive(Clone, Debug)]
pub struct Shard {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Its header.
    pub info: ShardInfo,
    /// Per pixel the exact sums and count, row by row from the top.
    pub film: Vec<FilmPixel>,
}

/// A stable 64-bit hash (FNV-1a) of `parts`, as 16 hex digits: the identity of a scene file's
/// bytes and the settings that change the image. Each part is preceded by its length, so that
/// moving bytes from one part to the next changes the hash.
pub fn identity(parts: &[&[u8]]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for b in bytes {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for part in parts {
        eat(&(part.len() as u64).to_le_bytes());
        eat(part);
    }
    format!("{h:016x}")
}

impl Shard {
    /// The image (linear RGB) and each pixel's coverage, exactly as `render` makes them from
    /// a film of these samples.
    pub fn image(&self) -> (Vec<[f32; 3]>, Vec<f32>) {
        let (mut image, mut coverage) = (Vec::new(), Vec::new());
        let samples = f64::from(self.info.samples);
        film::image_into(
            &self.film,
            self.info.counted,
            |_| samples,
            &mut image,
            Some(&mut coverage),
        );
        (image, coverage)
    }

    /// Whether the EXR has an alpha channel: the background is cut out.
    fn has_alpha(&self) -> bool {
        self.info.counted && self.info.background != "env"
    }

    /// The shard as an EXR file's bytes ([`Shard::write_exr`]).
    pub fn encode(&self) -> Result<Vec<u8>> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        self.write_exr(&mut bytes)
            .map_err(|e| anyhow::anyhow!("cannot encode EXR: {e}"))?;
        Ok(bytes.into_inner())
    }

    /// The channels of the shard's EXR in the file's order (sorted by name), each with what it
    /// holds.
    fn channels(&self) -> Vec<(&'static str, Holds)> {
        let mut channels = vec![
            ("R", Holds::Image(0)),
            ("G", Holds::Image(1)),
            ("B", Holds::Image(2)),
        ];
        if self.has_alpha() {
            // Premultiplied, as `render` writes it.
            channels.push(("A", Holds::Coverage));
        }
        for (lane, (hi, lo)) in FILM_CHANNELS.iter().enumerate() {
            channels.push((hi, Holds::Film { lane, shift: 32 }));
            channels.push((lo, Holds::Film { lane, shift: 0 }));
        }
        channels.sort_by_key(|(name, _)| *name);
        channels
    }

    /// Writes the shard as an uncompressed scan-line EXR, line by line from the film (no whole
    /// channel or file is built in memory). Uncompressed because a merge reads every film
    /// channel of every shard: RLE's decoding was most of a merge's time (docs/farm.md), and
    /// its film sums, noise in their low bits, hardly compress.
    pub fn write_exr(&self, out: impl std::io::Write + std::io::Seek) -> std::io::Result<()> {
        let w = self.width as usize;
        if self.film.len() != w * self.height as usize {
            return Err(std::io::Error::other("the film is not of the shard's size"));
        }
        self.write_exr_rows(out, |y, row| {
            row.copy_from_slice(&self.film[y * w..][..w]);
            Ok(())
        })
    }

    /// [`Shard::write_exr`] of a film that `fill_row(y, row)` gives row by row, top to bottom
    /// (`row` zeroed before each call), instead of this shard's `film`.
    pub fn write_exr_rows(
        &self,
        out: impl std::io::Write + std::io::Seek,
        mut fill_row: impl FnMut(usize, &mut [FilmPixel]) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        use exr::block::{BlockIndex, UncompressedBlock, writer::ChunksWriter};
        use exr::meta::attribute::{ChannelDescription, SampleType};
        use exr::prelude::*;
        let (w, h) = (self.width as usize, self.height as usize);
        if w == 0 || h == 0 {
            return Err(std::io::Error::other("a shard of no pixels"));
        }
        let channels = self.channels();
        let descriptions = channels
            .iter()
            .map(|(name, sample)| {
                let kind = match sample {
                    Holds::Film { .. } => SampleType::U32,
                    _ => SampleType::F32,
                };
                ChannelDescription::named(*name, kind)
            })
            .collect();
        let mut attributes = LayerAttributes::default();
        let info = serde_json::to_string(&self.info).map_err(std::io::Error::other)?;
        // The only custom attribute: the header's bytes do not depend on a map's order.
        attributes.other.insert(
            Text::from(ATTRIBUTE),
            AttributeValue::Text(Text::from(info.as_str())),
        );
        let header = exr::meta::header::Header::new(Text::from(""), (w, h), descriptions)
            .with_encoding(
                Compression::Uncompressed,
                exr::meta::BlockDescription::ScanLines,
                LineOrder::Increasing,
            )
            .with_attributes(attributes);
        let samples = f64::from(self.info.samples);
        let (mut image, mut coverage) = (Vec::new(), Vec::new());
        let mut row = vec![[0; 4]; w];
        exr::block::write(
            out,
            std::iter::once(header).collect(),
            true,
            |meta, writer| {
                let mut blocks = writer.sequential_blocks_compressor(&meta);
                // One line a block, its channels one after the other (native byte order: the
                // writer makes it little-endian).
                for y in 0..h {
                    row.fill([0; 4]);
                    fill_row(y, &mut row)?;
                    let row = &row;
                    film::image_into(
                        row,
                        self.info.counted,
                        |_| samples,
                        &mut image,
                        Some(&mut coverage),
                    );
                    let mut data = Vec::with_capacity(channels.len() * 4 * w);
                    for (_, sample) in &channels {
                        match *sample {
                            Holds::Image(c) => {
                                data.extend(image.iter().flat_map(|p| p[c].to_ne_bytes()));
                            }
                            Holds::Coverage => {
                                data.extend(coverage.iter().flat_map(|a| a.to_ne_bytes()));
                            }
                            Holds::Film { lane, shift } => data.extend(
                                row.iter()
                                    .flat_map(|p| ((p[lane] >> shift) as u32).to_ne_bytes()),
                            ),
                        }
                    }
                    let index = BlockIndex {
                        layer: 0,
                        pixel_position: Vec2(0, y),
                        pixel_size: Vec2(w, 1),
                        level: Vec2(0, 0),
                    };
                    blocks.compress_block(y, UncompressedBlock { index, data })?;
                }
                Ok(())
            },
        )
        .map_err(|e| match e {
            exr::error::Error::Io(e) => e,
            e => std::io::Error::other(e.to_string()),
        })
    }

    /// Reads a shard EXR; one line naming the file and what is wrong otherwise.
    pub fn read(path: &Path) -> Result<Shard> {
        let mut shard = Shard::read_header(path)?;
        shard.film = vec![[0; 4]; shard.width as usize * shard.height as usize];
        let info = shard.add_file(path)?;
        shard.info = info;
        Ok(shard)
    }

    /// Adds the film of the shard EXR at `path` (of this shard's size) to this shard's film,
    /// and returns that shard's header. The film's channels are read straight from the file's
    /// blocks as they are decompressed (on every core), each pixel's halves joined and added
    /// where they land: no channel is copied out whole, and the image channels are skipped.
    pub fn add_file(&mut self, path: &Path) -> Result<ShardInfo> {
        use exr::block::reader::ChunksReader;
        let shown = path.display();
        let (reader, info, layout) = open_blocks(path, self.width, self.height)?;
        let film = &mut self.film;
        if film.len() != layout.width * self.height as usize {
            bail!("{shown}: the film to add to is not of the shard's size");
        }
        reader
            .all_chunks(false)
            .map_err(|e| cannot_read(path, e))?
            .decompress_parallel(false, |_, block| layout.add_block(film, &block))
            .map_err(|e| cannot_read(path, e))?;
        Ok(info)
    }

    /// Reads only a shard EXR's header (no pixel): a shard with an empty film.
    pub fn read_header(path: &Path) -> Result<Shard> {
        let meta = exr::meta::MetaData::read_from_file(path, false)
            .map_err(|e| anyhow::anyhow!("{}: cannot read EXR: {e}", path.display()))?;
        let Some(header) = meta.headers.first() else {
            bail!("{}: an EXR without layers", path.display());
        };
        Ok(Shard {
            width: header.layer_size.width() as u32,
            height: header.layer_size.height() as u32,
            info: info_of(path, &header.own_attributes)?,
            film: Vec::new(),
        })
    }
}

/// An EXR reader of the shard at `path`, past its header, with the header's [`ShardInfo`] and
/// where its film lies in a block; one line naming the file and the problem otherwise, also
/// when it is not of `width` × `height` pixels.
fn open_blocks(
    path: &Path,
    width: u32,
    height: u32,
) -> Result<(
    exr::block::reader::Reader<std::io::BufReader<std::fs::File>>,
    ShardInfo,
    FilmLayout,
)> {
    let shown = path.display();
    let file = std::fs::File::open(path).map_err(|e| anyhow::anyhow!("{shown}: {e}"))?;
    let reader =
        exr::block::read(std::io::BufReader::new(file), false).map_err(|e| cannot_read(path, e))?;
    let Some(header) = reader.meta_data().headers.first() else {
        bail!("{shown}: an EXR without layers");
    };
    let info = info_of(path, &header.own_attributes)?;
    let (w, h) = (header.layer_size.width(), header.layer_size.height());
    if (w, h) != (width as usize, height as usize) {
        bail!("{shown}: {w}×{h} pixels, not {width}×{height}");
    }
    let layout = FilmLayout::of(path, header)?;
    Ok((reader, info, layout))
}

/// `path`'s EXR error as one line.
fn cannot_read(path: &Path, e: exr::error::Error) -> anyhow::Error {
    anyhow::anyhow!("{}: cannot read EXR: {e}", path.display())
}

/// Where a shard EXR's film lies in its blocks: lines hold each channel's samples in turn, in
/// the header's (sorted) order.
struct FilmLayout {
    /// The image's width and height in pixels.
    width: usize,
    height: usize,
    /// Each film lane's high and low channel: the bytes a pixel of the channels before it in a
    /// line (a line of `n` pixels holds the channel from this times `n` on).
    lanes: [(usize, usize); 4],
    /// The bytes of a pixel, all channels.
    pixel_bytes: usize,
}

impl FilmLayout {
    /// The layout of the shard EXR at `path` with this `header`; one line if a film channel
    /// is missing or not u32.
    fn of(path: &Path, header: &exr::meta::header::Header) -> Result<FilmLayout> {
        let channels = &header.channels.list;
        let before = |i: usize| -> usize {
            let sizes = channels[..i].iter();
            sizes.map(|c| c.sample_type.bytes_per_sample()).sum()
        };
        let place = |name: &str| {
            let at = channels.iter().position(|c| c.name.eq(name));
            match at.map(|i| (i, channels[i].sample_type)) {
                Some((i, exr::meta::attribute::SampleType::U32)) => Ok(before(i)),
                _ => Err(anyhow::anyhow!(
                    "{}: the shard has no u32 channel {name}",
                    path.display()
                )),
            }
        };
        let mut lanes = [(0, 0); 4];
        for (lane, (hi, lo)) in FILM_CHANNELS.iter().enumerate() {
            lanes[lane] = (place(hi)?, place(lo)?);
        }
        Ok(FilmLayout {
            width: header.layer_size.width(),
            height: header.layer_size.height(),
            lanes,
            pixel_bytes: before(channels.len()),
        })
    }

    /// Adds a decompressed block's film to `film` (the whole image's), each pixel's halves
    /// joined and added where they land.
    fn add_block(
        &self,
        film: &mut [FilmPixel],
        block: &exr::block::UncompressedBlock,
    ) -> exr::error::UnitResult {
        let (x0, y0) = (
            block.index.pixel_position.x(),
            block.index.pixel_position.y(),
        );
        let (bw, bh) = (
            block.index.pixel_size.width(),
            block.index.pixel_size.height(),
        );
        if block.index.layer != 0 || x0 + bw > self.width || y0 + bh > self.height {
            return Err(exr::error::Error::Invalid(
                "a block outside the image".into(),
            ));
        }
        let rows = &mut film[y0 * self.width..];
        self.add_lines(rows, (self.width, x0), (bw, bh), &block.data)
    }

    /// Adds the film of `data`, `lines` lines of `bw` pixels, into `rows` (of `stride` pixels a
    /// row) from column `x0` on.
    fn add_lines(
        &self,
        rows: &mut [FilmPixel],
        (stride, x0): (usize, usize),
        (bw, lines): (usize, usize),
        data: &[u8],
    ) -> exr::error::UnitResult {
        // A line holds each channel's `bw` samples in turn.
        let line_bytes = self.pixel_bytes * bw;
        if lines == 0
            || data.len() != line_bytes * lines
            || (lines - 1) * stride + x0 + bw > rows.len()
        {
            return Err(exr::error::Error::Invalid(
                "a block of the wrong size".into(),
            ));
        }
        for (row, line) in data.chunks_exact(line_bytes).enumerate() {
            let pixels = &mut rows[row * stride + x0..][..bw];
            for (lane, &(hi, lo)) in self.lanes.iter().enumerate() {
                let his = line[hi * bw..][..4 * bw].chunks_exact(4);
                let los = line[lo * bw..][..4 * bw].chunks_exact(4);
                for (p, (hi, lo)) in pixels.iter_mut().zip(his.zip(los)) {
                    let half = |b: &[u8]| u64::from(u32::from_ne_bytes([b[0], b[1], b[2], b[3]]));
                    p[lane] = p[lane].saturating_add(half(hi) << 32 | half(lo));
                }
            }
        }
        Ok(())
    }
}

/// A shard EXR read one line at a time, top to bottom, to add its film to a merge's line by
/// line: a merge then holds a line of each shard and of the output, not whole films (a 4K
/// film is 265 MB of fresh memory, whose page faults took most of a merge's CPU time).
pub struct LineReader {
    path: std::path::PathBuf,
    blocks: exr::block::reader::SequentialBlockDecompressor<
        exr::block::reader::AllChunksReader<std::io::BufReader<std::fs::File>>,
    >,
    layout: FilmLayout,
    /// The next line.
    y: usize,
}

impl LineReader {
    /// Opens the shard EXR at `path`, of `shard`'s size and header (read before:
    /// [`Shard::read_header`]); `None` when its blocks are not single lines in increasing
    /// order (another encoder's, tiles or several lines a block): read it whole then
    /// ([`Shard::add_file`]).
    pub fn open(path: &Path, shard: &Shard) -> Result<Option<LineReader>> {
        use exr::block::reader::ChunksReader;
        use exr::meta::{BlockDescription, attribute::LineOrder};
        let (reader, info, layout) = open_blocks(path, shard.width, shard.height)?;
        if info != shard.info {
            bail!("{}: changed while it was merged", path.display());
        }
        let header = &reader.meta_data().headers[0];
        let by_line = header.blocks == BlockDescription::ScanLines
            && header.compression.scan_lines_per_block() == 1
            && header.line_order == LineOrder::Increasing;
        if !by_line {
            return Ok(None);
        }
        let blocks = reader
            .all_chunks(false)
            .map_err(|e| cannot_read(path, e))?
            .sequential_decompressor(false);
        Ok(Some(LineReader {
            path: path.to_path_buf(),
            blocks,
            layout,
            y: 0,
        }))
    }

    /// Adds the film of the shard's next line to `row`.
    pub fn add_line(&mut self, row: &mut [FilmPixel]) -> Result<()> {
        let path = &self.path;
        let block = match self.blocks.next() {
            Some(block) => block.map_err(|e| cannot_read(path, e))?,
            None => bail!("{}: line {} is missing", path.display(), self.y),
        };
        let index = block.index;
        if (
            index.layer,
            index.pixel_position.x(),
            index.pixel_position.y(),
        ) != (0, 0, self.y)
            || index.pixel_size.width() != row.len()
            || index.pixel_size.height() != 1
        {
            bail!(
                "{}: its blocks are not the lines in order (line {} expected)",
                path.display(),
                self.y
            );
        }
        self.y += 1;
        let width = row.len();
        self.layout
            .add_lines(row, (width, 0), (width, 1), &block.data)
            .map_err(|e| cannot_read(path, e))
    }
}

/// The [`ShardInfo`] of a layer's attributes; one line naming `path` and the problem otherwise.
fn info_of(path: &Path, attributes: &exr::meta::header::LayerAttributes) -> Result<ShardInfo> {
    use exr::prelude::*;
    let shown = path.display();
    let info = match attributes.other.get(&Text::from(ATTRIBUTE)) {
        Some(AttributeValue::Text(t)) => serde_json::from_str::<ShardInfo>(&t.to_string())
            .map_err(|e| anyhow::anyhow!("{shown}: the shard header is damaged: {e}"))?,
        _ => bail!("{shown}: not a shard (no {ATTRIBUTE} header: render it with --sample-start)"),
    };
    if info.samples == 0 || info.sample_start.checked_add(info.samples).is_none() {
        bail!(
            "{shown}: the shard header's range ({} samples from {}) is empty or past the sequence",
            info.samples,
            info.sample_start
        );
    }
    Ok(info)
}

/// The header of the merge of shards whose headers are `shards` (films not needed), after
/// sorting them by their ranges. Refused, with one line naming the files: shards of another
/// size, scene or settings (another identity), PNG settings or background; overlapping
/// ranges; a gap between ranges (a missing shard). The first element of each pair names the
/// shard in messages.
pub fn check<N: std::fmt::Display>(shards: &mut [(N, Shard)]) -> Result<Shard> {
    shards.sort_by_key(|(_, s)| s.info.sample_start);
    let Some(((first_name, first), rest)) = shards.split_first() else {
        bail!("no shard to merge");
    };
    let mut sum = Shard {
        film: Vec::new(),
        ..first.clone()
    };
    let mut last_name = first_name;
    for (name, s) in rest {
        let (a, b) = (&sum.info, &s.info);
        if (s.width, s.height) != (sum.width, sum.height) {
            bail!(
                "{name}: {}×{} pixels, but {first_name} has {}×{}",
                s.width,
                s.height,
                sum.width,
                sum.height
            );
        }
        if b.identity != a.identity {
            bail!(
                "{name}: another scene or settings than {first_name} (identity {} against {})",
                b.identity,
                a.identity
            );
        }
        for (what, x, y) in [
            ("background", &b.background, &a.background),
            ("tone curve", &b.tonemap, &a.tonemap),
        ] {
            if x != y {
                bail!("{name}: {what} {x}, but {first_name} has {y}");
            }
        }
        if b.exposure != a.exposure {
            bail!("{name}: another exposure than {first_name}");
        }
        let end = a.sample_start + a.samples;
        if b.sample_start < end {
            bail!(
                "{name}: samples {}…{} overlap those of {last_name} (up to {})",
                b.sample_start,
                b.sample_start + b.samples - 1,
                end - 1
            );
        }
        if b.sample_start > end {
            bail!(
                "samples {end}…{} are missing: no shard between {last_name} and {name}",
                b.sample_start - 1
            );
        }
        sum.info.samples += b.samples;
        for (x, y) in [
            (&mut sum.info.kernel, &b.kernel),
            (&mut sum.info.device, &b.device),
        ] {
            if x != y {
                *x = "mixed".into();
            }
        }
        last_name = name;
    }
    Ok(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shard(start: u32, samples: u32, value: u64) -> Shard {
        Shard {
            width: 2,
            height: 1,
            info: ShardInfo {
                sample_start: start,
                samples,
                identity: identity(&[b"scene"]),
                counted: false,
                background: "env".into(),
                exposure: None,
                tonemap: "neutral".into(),
                scene: "scene.glb".into(),
                kernel: "megakernel".into(),
                device: "cpu".into(),
            },
            film: vec![[value << 33, value, 0, u64::from(samples)]; 2],
        }
    }

    #[test]
    fn a_shard_survives_its_exr() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.exr");
        let s = shard(16, 8, 12345);
        std::fs::write(&path, s.encode().unwrap()).unwrap();
        let back = Shard::read(&path).unwrap();
        assert_eq!(back.info, s.info);
        assert_eq!(back.film, s.film);
        // The RGB channels are the image, as a plain EXR reader sees it.
        let (_, _, rgb) = crate::image_io::read_exr(&path).unwrap();
        assert_eq!(rgb, s.image().0);
    }

    /// `s` as an RLE EXR in 64-pixel tiles, the same channels and header: a shard as another
    /// tool may rewrite it.
    fn encode_in_tiles(s: &Shard) -> Vec<u8> {
        use exr::prelude::*;
        let (image, coverage) = s.image();
        let channels = s.channels().into_iter().map(|(name, holds)| {
            let samples = match holds {
                Holds::Image(c) => FlatSamples::F32(image.iter().map(|p| p[c]).collect()),
                Holds::Coverage => FlatSamples::F32(coverage.clone()),
                Holds::Film { lane, shift } => {
                    FlatSamples::U32(s.film.iter().map(|p| (p[lane] >> shift) as u32).collect())
                }
            };
            AnyChannel::new(name, samples)
        });
        let mut attributes = LayerAttributes::default();
        let info = serde_json::to_string(&s.info).unwrap();
        attributes.other.insert(
            Text::from(ATTRIBUTE),
            AttributeValue::Text(Text::from(info.as_str())),
        );
        crate::image_io::encode_exr_layer(s.width, s.height, attributes, channels.collect())
            .unwrap()
    }

    #[test]
    fn shards_in_lines_are_read_a_line_at_a_time_others_whole() {
        let dir = tempfile::tempdir().unwrap();
        // Distinct sums in every pixel and lane, high halves included.
        let mut s = shard(0, 8, 0);
        (s.width, s.height) = (70, 3);
        s.film = (0..70 * 3u64)
            .map(|i| [i << 33 | i, i * 7, (i << 40) + 3, 8])
            .collect();
        let lines = dir.path().join("lines.exr");
        std::fs::write(&lines, s.encode().unwrap()).unwrap();
        let tiles = dir.path().join("tiles.exr");
        std::fs::write(&tiles, encode_in_tiles(&s)).unwrap();
        let header = Shard::read_header(&lines).unwrap();
        let mut reader = LineReader::open(&lines, &header)
            .unwrap()
            .expect("a line a block");
        let mut film = Vec::new();
        for _ in 0..3 {
            let mut row = vec![[0; 4]; 70];
            reader.add_line(&mut row).unwrap();
            film.extend(row);
        }
        assert_eq!(film, s.film);
        let mut row = vec![[0; 4]; 70];
        assert!(
            reader
                .add_line(&mut row)
                .unwrap_err()
                .to_string()
                .contains("line 3 is missing")
        );
        // Tiles: not a line a block, read whole, to the same film.
        assert!(LineReader::open(&tiles, &header).unwrap().is_none());
        assert_eq!(Shard::read(&tiles).unwrap().film, s.film);
        assert_eq!(Shard::read(&lines).unwrap().film, s.film);
    }

    #[test]
    fn merging_adds_the_sums_in_any_file_order() {
        let named = |s: Shard| (format!("{}.exr", s.info.sample_start), s);
        let mut shards = vec![named(shard(8, 4, 3)), named(shard(0, 8, 5))];
        let mut m = check(&mut shards).unwrap();
        assert_eq!((m.info.sample_start, m.info.samples), (0, 12));
        m.film = vec![[0; 4]; 2];
        for (_, s) in shards {
            film::add_films(&mut m.film, &s.film);
        }
        assert_eq!(m.film[0], [8 << 33, 8, 0, 12]);
    }

    #[test]
    fn merging_refuses_overlaps_gaps_and_other_settings() {
        let named = |s: Shard| (format!("{}.exr", s.info.sample_start), s);
        let err = |v: Vec<Shard>| {
            let mut named: Vec<_> = v.into_iter().map(named).collect();
            check(&mut named).unwrap_err().to_string()
        };
        assert!(err(vec![shard(0, 8, 1), shard(4, 8, 1)]).contains("overlap"));
        assert!(err(vec![shard(0, 8, 1), shard(12, 8, 1)]).contains("samples 8…11 are missing"));
        let mut other = shard(8, 8, 1);
        other.info.identity = identity(&[b"another scene"]);
        assert!(err(vec![shard(0, 8, 1), other]).contains("another scene or settings"));
        let mut wide = shard(8, 8, 1);
        wide.width = 3;
        wide.film.push([0; 4]);
        assert!(err(vec![shard(0, 8, 1), wide]).contains("3×1 pixels"));
    }

    #[test]
    fn the_identity_separates_its_parts() {
        assert_ne!(identity(&[b"ab", b"c"]), identity(&[b"a", b"bc"]));
        assert_eq!(identity(&[b"x"]), identity(&[b"x"]));
    }
}
