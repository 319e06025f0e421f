//! Adaptive sampling's heat maps (docs/adaptive-sampling.md): the display shows, instead of the
//! image, the samples each pixel took or its error estimate, on one palette from blue (cold:
//! few samples, error well under the threshold) through green to red (hot), with the scale the
//! overlay's legend prints.

/// What the display shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HeatMap {
    /// The image.
    #[default]
    Off,
    /// The samples each pixel took, from the fewest (blue) to the most (red).
    Samples,
    /// Each pixel's relative error (the estimate the adaptive sampler stops pixels on),
    /// against the noise threshold on a log scale: [`ERROR_SPAN`] times under it blue, at it
    /// green, as many times over it red.
    Error,
}

/// The error map's range on either side of the threshold, as a factor.
pub const ERROR_SPAN: f32 = 4.0;

impl HeatMap {
    /// The next view in the M key's cycle: image, samples, error, image.
    pub fn next(self) -> HeatMap {
        match self {
            HeatMap::Off => HeatMap::Samples,
            HeatMap::Samples => HeatMap::Error,
            HeatMap::Error => HeatMap::Off,
        }
    }

    /// Its name, for the overlay and the stats file.
    pub fn name(self) -> &'static str {
        match self {
            HeatMap::Off => "image",
            HeatMap::Samples => "samples per pixel",
            HeatMap::Error => "error",
        }
    }
}

/// The palette at `t` in [0, 1]: blue, green at ½, red.
pub fn palette(t: f32) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    [
        (2.0 * t - 1.0).clamp(0.0, 1.0),
        1.0 - (2.0 * t - 1.0).abs(),
        (1.0 - 2.0 * t).clamp(0.0, 1.0),
    ]
    .map(|c| (c * 255.0).round() as u8)
}

fn rgba(ts: impl Iterator<Item = f32>) -> Vec<u8> {
    ts.flat_map(|t| {
        let [r, g, b] = palette(t);
        [r, g, b, 255]
    })
    .collect()
}

/// The fewest and the most samples any pixel took (the samples map's scale).
pub fn samples_range(samples: &[u32]) -> (u32, u32) {
    let lo = samples.iter().copied().min().unwrap_or(0);
    let hi = samples.iter().copied().max().unwrap_or(0);
    (lo, hi)
}

/// Samples per pixel as RGBA8, from blue (the fewest any pixel took) to red (the most), so
/// that converged regions read as cold; all blue when every pixel took as many.
pub fn samples_rgba(samples: &[u32]) -> Vec<u8> {
    let (lo, hi) = samples_range(samples);
    let span = (hi - lo) as f32;
    rgba(samples.iter().map(|&s| match span > 0.0 {
        true => (s - lo) as f32 / span,
        false => 0.0,
    }))
}

/// Error estimates as RGBA8 against `threshold`: log(error / threshold) from −log
/// [`ERROR_SPAN`] (blue) through 0 (green) to +log [`ERROR_SPAN`] (red); a pixel without an
/// estimate yet (no samples: infinite error) is red, one of error 0 blue.
pub fn error_rgba(errors: &[f32], threshold: f32) -> Vec<u8> {
    let span = ERROR_SPAN.ln();
    rgba(errors.iter().map(|&e| match e.is_nan() {
        true => 1.0,
        false => 0.5 + 0.5 * (e / threshold).ln() / span,
    }))
}

/// The mean of the finite error estimates (0 without any).
pub fn mean_error(errors: &[f32]) -> f64 {
    let finite = errors.iter().filter(|e| e.is_finite());
    let n = finite.clone().count();
    finite.map(|&e| f64::from(e)).sum::<f64>() / n.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_samples_map_runs_from_blue_through_green_to_red() {
        let rgba = samples_rgba(&[16, 40, 64, 16]);
        assert_eq!(&rgba[0..4], &[0, 0, 255, 255], "the fewest: blue");
        assert_eq!(&rgba[4..8], &[0, 255, 0, 255], "half way: green");
        assert_eq!(&rgba[8..12], &[255, 0, 0, 255], "the most: red");
        assert_eq!(&rgba[12..16], &rgba[0..4]);
        // One count everywhere (all converged at once): all blue, no division by zero.
        assert_eq!(samples_rgba(&[32, 32]), [0, 0, 255, 255, 0, 0, 255, 255]);
    }

    #[test]
    fn the_error_map_is_green_at_the_threshold_on_a_log_scale() {
        let t = 0.01;
        let rgba = error_rgba(&[t, t / ERROR_SPAN, t * ERROR_SPAN, t / 100.0, 0.0], t);
        assert_eq!(&rgba[0..4], &[0, 255, 0, 255], "at the threshold: green");
        assert_eq!(&rgba[4..8], &[0, 0, 255, 255], "a span under: blue");
        assert_eq!(&rgba[8..12], &[255, 0, 0, 255], "a span over: red");
        assert_eq!(&rgba[12..16], &rgba[4..8], "further under: still blue");
        assert_eq!(&rgba[16..20], &rgba[4..8], "no error: blue");
        // Twice the threshold is half way from green to red: warmer, not yet red.
        let [r, g, b] = palette(0.5 + 0.5 * 2f32.ln() / ERROR_SPAN.ln());
        assert_eq!((r, g, b), (128, 128, 0));
        assert_eq!(&error_rgba(&[2.0 * t], t)[0..3], &[r, g, b]);
        // No estimate yet: hot.
        assert_eq!(&error_rgba(&[f32::INFINITY], t)[0..3], &[255, 0, 0]);
    }

    #[test]
    fn m_cycles_image_samples_error() {
        let mut h = HeatMap::Off;
        let seen: Vec<_> = (0..4)
            .map(|_| {
                h = h.next();
                h
            })
            .collect();
        assert_eq!(
            seen,
            [
                HeatMap::Samples,
                HeatMap::Error,
                HeatMap::Off,
                HeatMap::Samples
            ]
        );
    }

    #[test]
    fn the_mean_error_leaves_out_pixels_without_an_estimate() {
        assert_eq!(mean_error(&[0.5, f32::INFINITY, 1.5]), 1.0);
        assert_eq!(mean_error(&[]), 0.0);
    }
}
