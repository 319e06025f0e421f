//! Exposure: automatic (metered on the converging film) or physical (EV100).
//!
//! Exposure is handled in stops, as [`super::tonemap::to_rgba8`] takes it: a pixel's radiance is
//! multiplied by 2^stops before the tone curve.
//!
//! **Metering.** The key of an image is the log-average (geometric mean) of the luminance of its
//! pixels, leaving out black ones (escaped paths, pixels without samples yet) and non-finite
//! ones, and trimming the brightest [`HIGHLIGHT_TRIM`] so that a few lamps or fireflies in view
//! do not darken the rest. Automatic exposure puts the key at middle grey
//! ([`MIDDLE_GREY`]), limited so that the 90th percentile stays below [`BRIGHT_LIMIT`] (a bright subject before a
//! dark background keeps its shading; lamps and the sun, a few percent of the image, may clip).
//!
//! **Settling.** [`AutoExposure`] takes the first metering as it is, then follows later ones
//! halfway per update, and not at all while they stay within [`DEAD_BAND`] stops of the current
//! value: the noise of a converging film moves the key by a fraction of a stop, which would
//! otherwise make the image pump as samples accumulate.
//!
//! **Incident metering.** What the first view of a scene (not an interior) uses: the light
//! falling on the subject, measured by the first-view probe as the radiance W of a white
//! diffuse surface there, is exposed so that W shows at [`WHITE`] ([`incident_stops`]). Every
//! material then shows its own albedo: a navy sofa stays navy, a white board white.
//!
//! **Physical mode.** A camera at EV100 maps radiance L to L / (1.2 · 2^EV100) (the saturation-
//! based calibration with K = 12.5, q = 0.65). A white diffuse surface under a 100 000 lux sun
//! has L ≈ 100 000/π ≈ 32 000, which EV100 15 maps to about 0.8.

/// The display value the key of the image is mapped to (before the tone curve).
pub const MIDDLE_GREY: f32 = 0.18;
/// Share of the brightest metered pixels left out of the key.
pub const HIGHLIGHT_TRIM: f32 = 0.03;
/// The 90th percentile of luminance may map at most to this (ACES: 0.9), so that a bright
/// subject in front of a dark background is not blown out.
pub const BRIGHT_LIMIT: f32 = 3.0;
/// The display value (before the tone curve) of a white diffuse surface under incident
/// metering: the Khronos Sample Viewer's calibration (exposure 1 under a white environment of
/// radiance 1), where PBR Neutral shows base colours as they are.
pub const WHITE: f32 = 1.0;
/// Changes of the metered exposure smaller than this (stops) are ignored once settled.
pub const DEAD_BAND: f32 = 0.3;
/// The most pixels metered (a regular subset of larger images).
pub const MAX_METERED: usize = 1 << 16;

/// Luminance of linear Rec.709 RGB.
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Statistics of the luminance of an image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metering {
    /// Log-average luminance of the metered pixels (the key).
    pub key: f32,
    /// 90th percentile luminance.
    pub p90: f32,
    /// Share of the image's pixels that were metered (finite and not black).
    pub coverage: f32,
}

/// Meters `image` (linear RGB); `None` when no pixel is finite and above black.
pub fn meter(image: &[[f32; 3]]) -> Option<Metering> {
    if image.is_empty() {
        return None;
    }
    let step = image.len().div_ceil(MAX_METERED);
    let mut lum: Vec<f32> = image
        .iter()
        .step_by(step)
        .map(|&p| luminance(p))
        .filter(|l| l.is_finite() && *l > 1e-12)
        .collect();
    if lum.is_empty() {
        return None;
    }
    let metered = image.len().div_ceil(step);
    let coverage = lum.len() as f32 / metered as f32;
    lum.sort_by(f32::total_cmp);
    let kept = ((lum.len() as f32 * (1.0 - HIGHLIGHT_TRIM)).ceil() as usize).clamp(1, lum.len());
    let log_sum: f64 = lum[..kept].iter().map(|&l| (l as f64).ln()).sum();
    let key = (log_sum / kept as f64).exp() as f32;
    let at = |q: f32| lum[((lum.len() as f32 * q) as usize).min(lum.len() - 1)];
    Some(Metering {
        key,
        p90: at(0.90),
        coverage,
    })
}

/// Pixels at least this much covered by the scene count as the subject.
pub const SUBJECT_COVERAGE: f32 = 0.5;
/// The subject is metered alone when it covers at least this share of the image.
pub const MIN_SUBJECT_SHARE: f32 = 0.02;

/// Meters the subject of `image`: the pixels whose camera rays mostly hit the scene
/// (`coverage` ≥ [`SUBJECT_COVERAGE`], see `Renderer::coverage`), so that a dark or bright
/// background (the environment seen past the model) does not set the exposure. The whole image
/// is metered without a coverage, or when the subject is under [`MIN_SUBJECT_SHARE`] of it.
pub fn meter_subject(image: &[[f32; 3]], coverage: Option<&[f32]>) -> Option<Metering> {
    let Some(coverage) = coverage.filter(|c| c.len() == image.len()) else {
        return meter(image);
    };
    let subject: Vec<[f32; 3]> = image
        .iter()
        .zip(coverage)
        .filter(|(_, a)| **a >= SUBJECT_COVERAGE)
        .map(|(p, _)| *p)
        .collect();
    if (subject.len() as f32) < MIN_SUBJECT_SHARE * image.len() as f32 {
        return meter(image);
    }
    meter(&subject)
}

/// The exposure in stops that the metering asks for: the key to middle grey, lowered where the
/// 90th percentile would go past [`BRIGHT_LIMIT`].
pub fn auto_stops(m: &Metering) -> f32 {
    let key_stops = (MIDDLE_GREY / m.key).log2();
    let bright_stops = (BRIGHT_LIMIT / m.p90).log2();
    key_stops.min(bright_stops)
}

/// The exposure in stops that shows a white diffuse surface of radiance `white` at [`WHITE`].
pub fn incident_stops(white: f64) -> f32 {
    (WHITE as f64 / white).log2() as f32
}

/// The exposure in stops of a camera at `ev100`: 2^stops = 1 / (1.2 · 2^EV100).
pub fn ev100_stops(ev100: f32) -> f32 {
    -(1.2f32.log2() + ev100)
}

/// The EV100 that corresponds to an exposure of `stops` (inverse of [`ev100_stops`]).
pub fn stops_ev100(stops: f32) -> f32 {
    -(1.2f32.log2() + stops)
}

/// How the exposure is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExposureMode {
    /// Metered on the image.
    Auto,
    /// Fixed, in stops.
    Manual(f32),
    /// Fixed, in stops, by incident metering of the first view ([`incident_stops`]).
    Incident(f32),
    /// A physical camera at this EV100.
    Ev100(f32),
}

impl ExposureMode {
    /// The exposure in stops for an image with metering `m` (auto mode falls back to 0 when the
    /// image is black).
    pub fn stops(self, m: Option<&Metering>) -> f32 {
        match self {
            ExposureMode::Auto => m.map_or(0.0, auto_stops),
            ExposureMode::Manual(s) | ExposureMode::Incident(s) => s,
            ExposureMode::Ev100(ev) => ev100_stops(ev),
        }
    }
}

/// Automatic exposure that settles quickly and then holds still (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AutoExposure {
    stops: Option<f32>,
}

impl AutoExposure {
    /// Forgets the current value: the next metering is taken as it is (a new scene or view).
    pub fn reset(&mut self) {
        self.stops = None;
    }

    /// The current exposure in stops, if metered yet.
    pub fn stops(&self) -> Option<f32> {
        self.stops
    }

    /// Takes in a new metering and returns the exposure to show.
    pub fn update(&mut self, m: Option<&Metering>) -> f32 {
        let Some(target) = m.map(auto_stops) else {
            return self.stops.unwrap_or(0.0);
        };
        let next = match self.stops {
            None => target,
            Some(s) if (target - s).abs() <= DEAD_BAND => s,
            Some(s) => s + 0.5 * (target - s),
        };
        self.stops = Some(next);
        next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random value in [0, 1).
    fn hash(i: u64) -> f32 {
        let mut x = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
        x ^= x >> 31;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 29;
        (x >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn a_grey_image_is_exposed_to_middle_grey_at_any_level() {
        for level in [1e-4f32, 0.18, 3.0, 25_000.0] {
            let image = vec![[level; 3]; 1000];
            let m = meter(&image).unwrap();
            let exposed = level * 2f32.powf(auto_stops(&m));
            assert!(
                (exposed - MIDDLE_GREY).abs() < 1e-3 * MIDDLE_GREY.max(exposed),
                "{level}"
            );
        }
    }

    #[test]
    fn black_and_broken_pixels_are_not_metered() {
        let mut image = vec![[0.5f32; 3]; 100];
        image.extend(vec![[0.0; 3]; 300]);
        image.push([f32::NAN, 0.0, 0.0]);
        image.push([f32::INFINITY; 3]);
        let m = meter(&image).unwrap();
        assert!((m.key - 0.5).abs() < 1e-4, "{m:?}");
        assert!((m.coverage - 100.0 / 402.0).abs() < 1e-4);
        assert!(meter(&[[0.0; 3]; 10]).is_none());
        assert!(meter(&[]).is_none());
    }

    #[test]
    fn a_few_bright_lamps_do_not_darken_the_subject() {
        let mut image = vec![[0.02f32; 3]; 990];
        image.extend(vec![[5000.0; 3]; 10]);
        let m = meter(&image).unwrap();
        assert!((m.key - 0.02).abs() < 1e-3, "{m:?}");
        // The key is brought up towards middle grey (the lamps clip, as they should).
        let stops = auto_stops(&m);
        assert!(stops > 2.0, "{stops}");
    }

    #[test]
    fn highlights_limit_the_exposure() {
        // Half the image dark, half bright: the bright half keeps its shading (at most
        // BRIGHT_LIMIT), though the key alone would push it a stop higher.
        let mut image = vec![[0.001f32; 3]; 500];
        image.extend(vec![[1.0; 3]; 500]);
        let m = meter(&image).unwrap();
        let stops = auto_stops(&m);
        assert!((2f32.powf(stops) - BRIGHT_LIMIT).abs() < 1e-3, "{stops}");
        assert!((MIDDLE_GREY / m.key).log2() > stops + 1.0);
        // Lamps on 5% of the image clip; they do not darken the rest.
        let mut image = vec![[0.1f32; 3]; 950];
        image.extend(vec![[100.0; 3]; 50]);
        let m = meter(&image).unwrap();
        assert_eq!(auto_stops(&m), (MIDDLE_GREY / m.key).log2());
        assert!(auto_stops(&m) > 0.5);
    }

    #[test]
    fn a_sunlit_white_surface_looks_right_at_ev100_15() {
        let radiance = 100_000.0 / std::f32::consts::PI;
        let exposed = radiance * 2f32.powf(ev100_stops(15.0));
        assert!((0.6..1.0).contains(&exposed), "{exposed}");
        assert!((stops_ev100(ev100_stops(12.3)) - 12.3).abs() < 1e-5);
        assert_eq!(ExposureMode::Ev100(15.0).stops(None), ev100_stops(15.0));
        assert_eq!(ExposureMode::Manual(-3.0).stops(None), -3.0);
    }

    /// A film converging on a scene of luminance 2 (half) and 0.1 (half): each sample is the
    /// true value times an exponential variate (a noisy path tracer), averaged over `spp`.
    fn film(spp: u32) -> Vec<[f32; 3]> {
        (0..4096u64)
            .map(|p| {
                let truth = if p % 2 == 0 { 2.0 } else { 0.1 };
                let mean: f32 = (0..spp as u64)
                    .map(|s| -(1.0 - hash(p * 1_000_003 + s)).ln())
                    .sum::<f32>()
                    / spp as f32;
                [truth * mean; 3]
            })
            .collect()
    }

    #[test]
    fn the_subject_is_metered_without_its_background() {
        // A mid-grey subject on half the image before a dark curtain: the whole image's key is
        // pulled down (overexposing the subject); the subject's is not.
        let image: Vec<[f32; 3]> = (0..1000)
            .map(|i| if i < 500 { [0.18; 3] } else { [0.002; 3] })
            .collect();
        let coverage: Vec<f32> = (0..1000).map(|i| if i < 500 { 1.0 } else { 0.0 }).collect();
        let whole = auto_stops(&meter(&image).unwrap());
        let subject = auto_stops(&meter_subject(&image, Some(&coverage)).unwrap());
        assert!(whole > 2.0, "{whole}");
        assert!(subject.abs() < 0.05, "{subject}");
        // A subject of a few pixels is not metered alone.
        let speck: Vec<f32> = (0..1000).map(|i| if i < 5 { 1.0 } else { 0.0 }).collect();
        assert_eq!(meter_subject(&image, Some(&speck)), meter(&image));
        assert_eq!(meter_subject(&image, None), meter(&image));
    }

    #[test]
    fn auto_exposure_settles_quickly_and_does_not_pump() {
        let converged = auto_stops(&meter(&film(4096)).unwrap());
        let mut auto = AutoExposure::default();
        let mut shown = Vec::new();
        for spp in [1u32, 2, 4, 8, 16, 32, 64, 128, 256, 512] {
            shown.push(auto.update(meter(&film(spp)).as_ref()));
        }
        // Within half a stop of the converged exposure from 8 spp on, and close at the end.
        for (i, s) in shown.iter().enumerate().skip(3) {
            assert!(
                (s - converged).abs() < 0.5,
                "update {i}: {s} vs {converged}"
            );
        }
        assert!((shown[9] - converged).abs() < DEAD_BAND + 0.05);
        // It moves monotonically (never back and forth) and rests once settled.
        let steps: Vec<f32> = shown.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(
            steps.iter().all(|d| *d >= 0.0) || steps.iter().all(|d| *d <= 0.0),
            "{shown:?}"
        );
        assert_eq!(shown[8], shown[9], "{shown:?}");
        auto.reset();
        assert_eq!(auto.stops(), None);
    }
}
