//! The small statistics the benchmarks report: medians, image error metrics and log-log slopes.

/// The median of `values` (the mean of the middle two for an even count); 0 for none.
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Error of an image against a reference, over every pixel and channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageError {
    /// Root mean squared error.
    pub rmse: f64,
    /// Relative mean squared error: the mean of (x − r)² / (r² + 0.01).
    pub relmse: f64,
}

/// RMSE and relMSE of `image` against `reference` (same size); non-finite pixels count as 0.
pub fn image_error(image: &[[f32; 3]], reference: &[[f32; 3]]) -> ImageError {
    assert_eq!(image.len(), reference.len(), "image sizes differ");
    let (mut se, mut rel) = (0.0f64, 0.0f64);
    for (p, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let x = if p[c].is_finite() { p[c] as f64 } else { 0.0 };
            let r = r[c] as f64;
            let d2 = (x - r) * (x - r);
            se += d2;
            rel += d2 / (r * r + 0.01);
        }
    }
    let n = (image.len() * 3).max(1) as f64;
    ImageError {
        rmse: (se / n).sqrt(),
        relmse: rel / n,
    }
}

/// The least-squares slope of ln(y) against ln(x) over the points with both positive and
/// finite; `None` with fewer than two such points or no spread in x.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 1e-12).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&[]), 0.0);
    }

    #[test]
    fn image_error_of_a_known_difference() {
        let reference = vec![[1.0, 0.0, 0.0]; 4];
        let image = vec![[2.0, 0.0, 0.0]; 4];
        let e = image_error(&image, &reference);
        // One channel in three is off by 1.
        assert!((e.rmse - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!((e.relmse - 1.0 / 1.01 / 3.0).abs() < 1e-12);
        assert_eq!(image_error(&reference, &reference).relmse, 0.0);
    }

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<(f64, f64)> = (1..8).map(|i| (i as f64, 5.0 / i as f64)).collect();
        assert!((log_log_slope(&pts).unwrap() + 1.0).abs() < 1e-12);
        assert_eq!(log_log_slope(&[(1.0, 1.0)]), None);
        assert_eq!(log_log_slope(&[(1.0, 1.0), (1.0, 2.0)]), None);
    }
}
