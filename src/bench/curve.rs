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
    /// CPU time of the process (all threads) over the renders so far: on a CPU device shared
    /// with other work, the renderer's own cost, which wall time mixes with the neighbours'.
    pub cpu_seconds: f64,
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

/// The time `steps` (in order of spp) take to reach `relmse`, by `time` (wall or CPU seconds):
/// interpolated on log–log axes between the steps around it, or past the last step extended as
/// an unbiased estimator's relMSE ∝ 1 / time; `None` when the first step is already below it
/// or a time is not positive.
pub fn time_to(steps: &[Step], relmse: f64, time: fn(&Step) -> f64) -> Option<f64> {
    let first = steps.first()?;
    if relmse > first.relmse || relmse <= 0.0 {
        return None;
    }
    for pair in steps.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        if (b.relmse..=a.relmse).contains(&relmse) && time(a) > 0.0 && time(b) > 0.0 {
            let f = (relmse / a.relmse).ln() / (b.relmse / a.relmse).ln();
            let f = if f.is_finite() { f } else { 0.0 };
            return Some((time(a).ln() + f * (time(b) / time(a)).ln()).exp());
        }
    }
    let last = steps.last()?;
    (time(last) > 0.0 && relmse <= last.relmse).then(|| time(last) * last.relmse / relmse)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_to_a_relmse_follows_the_curve_and_past_it_one_over_time() {
        let step = |spp: u32, seconds: f64, relmse: f64| Step {
            spp,
            seconds,
            kernel_seconds: 0.0,
            cpu_seconds: 2.0 * seconds,
            rmse: 0.0,
            relmse,
        };
        let steps = [step(1, 1.0, 1.0), step(2, 2.0, 0.5), step(4, 4.0, 0.25)];
        let wall = |s: &Step| s.seconds;
        // On the curve: exact at a step, log-log between steps.
        assert_eq!(time_to(&steps, 0.5, wall), Some(2.0));
        assert!((time_to(&steps, 0.7, wall).unwrap() - 1.0 / 0.7).abs() < 1e-12);
        // Past the last step: relMSE ∝ 1 / time; by CPU time, twice the wall time here.
        assert!((time_to(&steps, 0.1, wall).unwrap() - 10.0).abs() < 1e-12);
        assert!((time_to(&steps, 0.1, |s| s.cpu_seconds).unwrap() - 20.0).abs() < 1e-12);
        // Above the first step's relMSE: unknown.
        assert_eq!(time_to(&steps, 2.0, wall), None);
    }

    #[test]
    fn a_one_over_n_curve_fits_slope_minus_one() {
        let steps = (0..8)
            .map(|i| {
                let spp = 1 << i;
                Step {
                    spp,
                    seconds: 0.01 * spp as f64,
                    kernel_seconds: 0.0,
                    cpu_seconds: 0.0,
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
