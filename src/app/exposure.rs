//! Automatic exposure in the viewer: decided once per view and held while the image converges.
//! The first image of a view with every bounce (the preview's one-bounce levels are darker than
//! the view) is metered, pooled in blocks so that one sample's noise does not bias the
//! log-average; the exposure shown then eases to it and stays there, whatever later samples
//! meter, until the view changes (camera, scene, lights or settings). Locked, it stays put
//! across views too.

use crate::render::exposure::{Metering, auto_stops, meter_subject};

/// Time constant of the easing to a new view's exposure, in seconds.
const EASE_SECONDS: f64 = 0.15;
/// Pixels per side of the blocks a young film is averaged over before metering.
const POOL: usize = 4;
/// From this many samples per pixel on the film is metered as it is.
const POOL_BELOW_SPP: u32 = 16;

/// The held automatic exposure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeldExposure {
    /// The exposure decided for the current view, in stops.
    target: Option<f32>,
    /// The exposure shown (easing toward `target`).
    shown: Option<f32>,
    /// The view `target` was decided for.
    view: Option<u64>,
    /// The lock button: no new decisions.
    pub locked: bool,
}

impl HeldExposure {
    /// Forgets the decision: the next view's first image is taken as it is (a new scene).
    pub fn reset(&mut self) {
        let locked = self.locked;
        *self = Self {
            locked,
            ..Self::default()
        };
    }

    /// Whether an image of `view` would decide the exposure.
    pub fn wants(&self, view: u64) -> bool {
        !self.locked && self.view != Some(view)
    }

    /// Decides the exposure of `view` from its metering (`None`: nothing to meter; the next
    /// image tries again). The very first decision is shown at once, later ones are eased to.
    pub fn decide(&mut self, view: u64, metering: Option<&Metering>) {
        if !self.wants(view) {
            return;
        }
        if let Some(m) = metering {
            let stops = auto_stops(m);
            self.target = Some(stops);
            self.shown.get_or_insert(stops);
            self.view = Some(view);
        }
    }

    /// Moves the shown exposure toward the decided one over `dt` seconds and returns it
    /// (`None` before the first decision).
    pub fn advance(&mut self, dt: f64) -> Option<f32> {
        let target = self.target?;
        let shown = self.shown.get_or_insert(target);
        let k = 1.0 - (-dt.max(0.0) / EASE_SECONDS).exp();
        *shown += (target - *shown) * k as f32;
        if (target - *shown).abs() < 0.01 {
            *shown = target;
        }
        Some(*shown)
    }

    /// Whether the shown exposure is still easing.
    pub fn settling(&self) -> bool {
        matches!((self.target, self.shown), (Some(t), Some(s)) if t != s)
    }
}

/// Meters a film of `width` columns (straight color; `coverage` when the background is cut
/// out) at `spp` samples per pixel, averaged in [`POOL`]-pixel blocks while young.
pub fn meter_film(
    pixels: &[[f32; 3]],
    coverage: Option<&[f32]>,
    width: usize,
    spp: u32,
) -> Option<Metering> {
    if spp >= POOL_BELOW_SPP || width < POOL {
        return meter_subject(pixels, coverage);
    }
    let (pooled, weights) = pool(pixels, coverage, width);
    meter_subject(&pooled, coverage.map(|_| weights.as_slice()))
}

/// Averages `POOL`×`POOL` blocks (partial ones at the edges); the coverage too.
fn pool(pixels: &[[f32; 3]], coverage: Option<&[f32]>, width: usize) -> (Vec<[f32; 3]>, Vec<f32>) {
    let height = pixels.len() / width;
    let (bw, bh) = (width.div_ceil(POOL), height.div_ceil(POOL));
    let mut sum = vec![[0.0f32; 3]; bw * bh];
    let mut cov = vec![0.0f32; bw * bh];
    let mut count = vec![0.0f32; bw * bh];
    for y in 0..height {
        for x in 0..width {
            let (i, b) = (y * width + x, (y / POOL) * bw + x / POOL);
            for c in 0..3 {
                sum[b][c] += pixels[i][c];
            }
            cov[b] += coverage.map_or(1.0, |c| c[i]);
            count[b] += 1.0;
        }
    }
    for b in 0..sum.len() {
        let n = count[b].max(1.0);
        sum[b] = sum[b].map(|v| v / n);
        cov[b] /= n;
    }
    (sum, cov)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metering(key: f32) -> Metering {
        let image = vec![[key; 3]; 64];
        meter_subject(&image, None).unwrap()
    }

    #[test]
    fn decided_once_per_view_eased_and_held() {
        let mut e = HeldExposure::default();
        e.decide(1, Some(&metering(0.5)));
        let first = e.advance(0.0).unwrap();
        // Later images of the same view change nothing, however they meter.
        e.decide(1, Some(&metering(0.05)));
        assert_eq!(e.advance(1.0), Some(first));
        // A new view is eased to: not at once, there after a second.
        e.decide(2, Some(&metering(0.05)));
        let step = e.advance(0.016).unwrap();
        assert!(step > first && e.settling());
        let settled = e.advance(1.0).unwrap();
        assert!(
            (settled - first - (0.5f32 / 0.05).log2()).abs() < 0.05,
            "{first} {settled}"
        );
        assert!(!e.settling());
        // Locked: views change, the exposure does not.
        e.locked = true;
        e.decide(3, Some(&metering(5.0)));
        assert_eq!(e.advance(1.0), Some(settled));
    }

    #[test]
    fn a_noisy_young_film_meters_like_a_converged_one() {
        // One pixel in sixteen found the light (16× brighter), as at one sample in a room lit
        // from outside: the log-average of the raw film is far off; pooled it is right.
        let width = 64;
        let converged: Vec<[f32; 3]> = vec![[1.0; 3]; width * width];
        let noisy: Vec<[f32; 3]> = (0..width * width)
            .map(|i| {
                let (x, y) = (i % width, i / width);
                if x % 4 == 0 && y % 4 == 0 {
                    [16.0; 3]
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let mean: f32 = noisy.iter().map(|p| p[0]).sum::<f32>() / noisy.len() as f32;
        assert!((mean - 1.0).abs() < 0.05, "{mean}");
        let truth = auto_stops(&meter_subject(&converged, None).unwrap());
        let pooled = auto_stops(&meter_film(&noisy, None, width, 1).unwrap());
        assert!((pooled - truth).abs() < 0.3, "pooled {pooled} vs {truth}");
        let raw = meter_subject(&noisy, None).map(|m| auto_stops(&m));
        assert!(
            raw.is_none_or(|r| (r - truth).abs() > 1.0),
            "raw {raw:?} vs {truth}"
        );
    }
}
