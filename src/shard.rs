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

    /// The shard as an EXR file's bytes.
    pub fn encode(&self) -> Result<Vec<u8>> {
        use exr::prelude::*;
        let (image, coverage) = self.image();
        let mut channels: Vec<AnyChannel<FlatSamples>> = (0..3)
            .map(|c| {
                AnyChannel::new(
                    ["R", "G", "B"][c],
                    FlatSamples::F32(image.iter().map(|p| p[c]).collect()),
                )
            })
            .collect();
        if self.has_alpha() {
            // Premultiplied, as `render` writes it.
            channels.push(AnyChannel::new("A", FlatSamples::F32(coverage)));
        }
        for (lane, (hi, lo)) in FILM_CHANNELS.iter().enumerate() {
            let part = |shift: u32| {
                FlatSamples::U32(
                    self.film
                        .iter()
                        .map(|p| (p[lane] >> shift) as u32)
                        .collect(),
                )
            };
            channels.push(AnyChannel::new(*hi, part(32)));
            channels.push(AnyChannel::new(*lo, part(0)));
        }
        let mut attributes = LayerAttributes::default();
        // The only custom attribute: the header's bytes do not depend on a map's order.
        attributes.other.insert(
            Text::from(ATTRIBUTE),
            AttributeValue::Text(Text::from(serde_json::to_string(&self.info)?.as_str())),
        );
        crate::image_io::encode_exr_layer(
            self.width,
            self.height,
            attributes,
            SmallVec::from_vec(channels),
        )
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
        let cannot = |e: exr::error::Error| anyhow::anyhow!("{shown}: cannot read EXR: {e}");
        let file = std::fs::File::open(path).map_err(|e| anyhow::anyhow!("{shown}: {e}"))?;
        let reader = exr::block::read(std::io::BufReader::new(file), false).map_err(cannot)?;
        let Some(header) = reader.meta_data().headers.first() else {
            bail!("{shown}: an EXR without layers");
        };
        let info = info_of(path, &header.own_attributes)?;
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        if (w, h) != (self.width as usize, self.height as usize) || self.film.len() != w * h {
            bail!(
                "{shown}: {w}×{h} pixels, not {}×{}",
                self.width,
                self.height
            );
        }
        // Each channel's place in a block's line: lines hold each channel's samples in turn,
        // in the header's (sorted) order.
        let channels = &header.channels.list;
        let place = |name: &str| {
            let at = channels.iter().position(|c| c.name.eq(name));
            match at.map(|i| (i, channels[i].sample_type)) {
                Some((i, exr::meta::attribute::SampleType::U32)) => Ok(i),
                _ => Err(anyhow::anyhow!(
                    "{shown}: the shard has no u32 channel {name}"
                )),
            }
        };
        let mut lanes = [(0, 0); 4];
        for (lane, (hi, lo)) in FILM_CHANNELS.iter().enumerate() {
            lanes[lane] = (place(hi)?, place(lo)?);
        }
        let sizes: Vec<usize> = channels
            .iter()
            .map(|c| c.sample_type.bytes_per_sample())
            .collect();
        let film = &mut self.film;
        reader
            .all_chunks(false)
            .map_err(cannot)?
            .decompress_parallel(false, |_, block| {
                let (x0, y0) = (
                    block.index.pixel_position.x(),
                    block.index.pixel_position.y(),
                );
                let (bw, bh) = (
                    block.index.pixel_size.width(),
                    block.index.pixel_size.height(),
                );
                if block.index.layer != 0 || x0 + bw > w || y0 + bh > h {
                    return Err(exr::error::Error::Invalid(
                        "a block outside the image".into(),
                    ));
                }
                // Where each channel starts in a line of the block.
                let mut starts = Vec::with_capacity(sizes.len());
                let mut line_bytes = 0;
                for s in &sizes {
                    starts.push(line_bytes);
                    line_bytes += s * bw;
                }
                if block.data.len() != line_bytes * bh {
                    return Err(exr::error::Error::Invalid(
                        "a block of the wrong size".into(),
                    ));
                }
                for (row, line) in block.data.chunks_exact(line_bytes).enumerate() {
                    let pixels = &mut film[(y0 + row) * w + x0..][..bw];
                    for (lane, &(hi, lo)) in lanes.iter().enumerate() {
                        let his = line[starts[hi]..][..4 * bw].chunks_exact(4);
                        let los = line[starts[lo]..][..4 * bw].chunks_exact(4);
                        for (p, (hi, lo)) in pixels.iter_mut().zip(his.zip(los)) {
                            let half =
                                |b: &[u8]| u64::from(u32::from_ne_bytes([b[0], b[1], b[2], b[3]]));
                            p[lane] = p[lane].saturating_add(half(hi) << 32 | half(lo));
                        }
                    }
                }
                Ok(())
            })
            .map_err(cannot)?;
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
