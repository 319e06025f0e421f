//! `penumbra merge SHARD… -o OUT.{exr,png}`: shards of `render --sample-start` added up into the
//! image one render of all their samples makes, bit for bit (`crate::shard`, docs/farm.md).

use super::MergeArgs;
use super::render::{encode_png, exposure_stops};
use crate::image_io::{Format, OutputFile};
use crate::render::background::Background;
use crate::render::exposure::ExposureMode;
use crate::render::tonemap::ToneMapper;
use crate::shard::{self, LineReader, Shard};
use anyhow::{Result, anyhow};
use std::path::Path;
use std::time::Instant;

/// A shard's path, shown in messages.
struct Named<'a>(&'a Path);

impl std::fmt::Display for Named<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.display().fmt(f)
    }
}

/// Reads the shards, refuses any that do not belong together (one line), and writes the sum:
/// an EXR is itself a shard of all the samples; a PNG is exposed and tone-mapped as the
/// shards' `render` options say (the exposure metered on the merged image unless it was fixed).
pub fn run(args: &MergeArgs) -> Result<()> {
    let started = Instant::now();
    let output = OutputFile::open(&args.output)?;
    // The headers first: shards that do not belong together are refused before any pixel is
    // read.
    let mut shards = args
        .shards
        .iter()
        .map(|path| Ok((Named(path), Shard::read_header(path)?)))
        .collect::<Result<Vec<_>>>()?;
    let count = shards.len();
    let mut merged = shard::check(&mut shards)?;
    let (w, h) = (merged.width, merged.height);
    if output.format == Format::Exr {
        // Shards stored a line a block (as `render` writes them) are added and written a line
        // at a time: no whole film in memory.
        let lines = shards
            .iter()
            .map(|(name, header)| LineReader::open(name.0, header))
            .collect::<Result<Option<Vec<_>>>>()?;
        if let Some(mut lines) = lines {
            // A shard's error while the output is written: reported as itself, not as a
            // failed write.
            let mut failed = None;
            let written = output.write_with(|out| {
                merged.write_exr_rows(out, |_, row| {
                    for shard in &mut lines {
                        if let Err(e) = shard.add_line(row) {
                            let line = e.to_string();
                            failed = Some(e);
                            return Err(std::io::Error::other(line));
                        }
                    }
                    Ok(())
                })
            });
            if let Some(e) = failed {
                return Err(e);
            }
            written?;
            report(args, count, &merged, started);
            return Ok(());
        }
    }
    // The headers were checked: each shard's film is now added to the sum as its blocks are
    // decompressed, so that a merge holds one film, not one per shard.
    merged.film = vec![[0; 4]; w as usize * h as usize];
    for (name, header) in &shards {
        if merged.add_file(name.0)? != header.info {
            anyhow::bail!("{name}: changed while it was merged");
        }
    }
    match output.format {
        Format::Exr => output.write_with(|out| merged.write_exr(out))?,
        Format::Png => {
            let info = &merged.info;
            let background: Background = info.background.parse().map_err(|e: String| {
                anyhow!(
                    "{}: the shard header's background: {e}",
                    args.shards[0].display()
                )
            })?;
            let tonemap = ToneMapper::from_arg(&info.tonemap).map_err(|e| {
                anyhow!(
                    "{}: the shard header's tone curve: {e}",
                    args.shards[0].display()
                )
            })?;
            let (image, coverage) = merged.image();
            let mode = info
                .exposure
                .map_or(ExposureMode::Auto, ExposureMode::Manual);
            let exposure = exposure_stops(&image, &coverage, background, mode);
            output.write(&encode_png(
                w, h, &image, &coverage, background, exposure, tonemap,
            )?)?;
        }
    }
    report(args, count, &merged, started);
    Ok(())
}

/// The line on stderr saying what a merge wrote.
fn report(args: &MergeArgs, count: usize, merged: &Shard, started: Instant) {
    let (w, h) = (merged.width, merged.height);
    let info = &merged.info;
    eprintln!(
        "penumbra: wrote {}: {count} shards, {w}×{h} pixels, samples {}…{} ({} spp), in {:.2} s",
        args.output.display(),
        info.sample_start,
        info.sample_start + info.samples - 1,
        info.samples,
        started.elapsed().as_secs_f64()
    );
}
