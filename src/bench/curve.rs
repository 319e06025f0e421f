//! A convergence curve: the error and time recorded at each step of one configuration's
//! renders, and the slopes and efficiency fitted to them (`bench converge` records them, the
//! plot draws them).

use super::stats::log_log_slope;

/// One recorded step.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Step {
    /// Samples per pixel in the film.
    pub spp: u32,
    /// Wall time of the renders so far (blocking calls; read-back and metrics excluded).
    pub seconds: f64,
    /// Kernel time of the renders so far, from profiling events.
    pub kernel_seconds: f64,
    /// Root mean squared error against the reference.
    pub rmse: f64,
    /// Mean of (x − r)² / (r² + 0.01) over pixels and channels.
    pub relmse: f64,
}

/// The steps of one configuration and what is fitted to them.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Curve {
    /// Configuration name.
    pub config: String,
    /// Steps, in order.
    pub steps: Vec<Step>,
    /// Slope of ln relMSE against ln wall time over the fitted steps that took at least 1/64
    /// of the last step's time (−1: unbiased).
    pub slope_time: Option<f64>,
    /// Slope of ln relMSE against ln spp over the fitted steps (not a timing).
    pub slope_spp: Option<f64>,
    /// 1 / (relMSE × seconds) at the last step.
    pub efficiency: f64,
}

impl Curve {
    /// The fits of `steps`: the slopes over the steps from `fit_from` spp on, and the
    /// efficiency at the last.
    pub fn fit(config: String, steps: Vec<Step>, fit_from: u32) -> Self {
        let fitted: Vec<&Step> = steps.iter().filter(|s| s.spp >= fit_from).collect();
        // Steps shorter than 1/64 of the last are left out of the time fit: there, fixed costs
        // per call (launch latency, a wave that does not fill the device) outweigh the
        // samples and would steepen the slope.
        let last_seconds = steps.last().map_or(0.0, |s| s.seconds);
        let slope_time = log_log_slope(
            &fitted
                .iter()
                .filter(|s| s.seconds >= last_seconds / 64.0)
                .map(|s| (s.seconds, s.relmse))
                .collect::<Vec<_>>(),
        );
        let slope_spp = log_log_slope(
            &fitted
                .iter()
                .map(|s| (s.spp as f64, s.relmse))
                .collect::<Vec<_>>(),
        );
        let efficiency = steps
            .last()
            .map_or(0.0, |s| 1.0 / (s.relmse * s.seconds).max(1e-300));
        Self {
            config,
            steps,
            slope_time,
            slope_spp,
            efficiency,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_one_over_n_curve_fits_slope_minus_one() {
        let steps = (0..8)
            .map(|i| {
                let spp = 1 << i;
                Step {
                    spp,
                    seconds: 0.01 * spp as f64,
                    kernel_seconds: 0.0,
                    rmse: 0.0,
                    relmse: 0.5 / spp as f64,
                }
            })
            .collect();
        let c = Curve::fit("mis".into(), steps, 4);
        assert!((c.slope_time.unwrap() + 1.0).abs() < 1e-9);
        assert!((c.slope_spp.unwrap() + 1.0).abs() < 1e-9);
        assert!((c.efficiency - 1.0 / (0.5 / 128.0 * 1.28)).abs() < 1e-6);
    }
}
