//! The convergence plot: relMSE against wall time on log–log axes, one curve per
//! configuration, with its fitted slope, and a slope −1 guide.

use super::curve::Curve;
use anyhow::{Result, anyhow};
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::Path;
use std::sync::Once;

/// Registers the font the plot's text uses (bundled bytes: there are no system fonts).
fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_err()
        {
            log::warn!("the plot font did not load; the plot's text may be missing");
        }
    });
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(174, 199, 232),
    RGBColor(214, 39, 40),
    RGBColor(255, 152, 150),
    RGBColor(44, 160, 44),
    RGBColor(152, 223, 138),
];

/// Writes the plot to `path` (PNG). `subtitle` names the device and date.
pub fn convergence(path: &Path, title: &str, subtitle: &str, curves: &[Curve]) -> Result<()> {
    register_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("{}: cannot draw the plot: {e}", path.display());
    let points: Vec<(f64, f64)> = curves
        .iter()
        .flat_map(|c| c.steps.iter().map(|s| (s.seconds, s.relmse)))
        .filter(|(t, e)| *t > 0.0 && *e > 0.0 && t.is_finite() && e.is_finite())
        .collect();
    if points.is_empty() {
        return Err(anyhow!("{}: nothing to plot", path.display()));
    }
    let (t0, t1) = points.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let (e0, e1) = points.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.1), b.max(p.1))
    });
    let (t0, t1, e0, e1) = (t0 / 1.5, t1 * 1.5, e0 / 1.5, e1 * 1.5);

    let root = BitMapBackend::new(path, (1000, 720)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let area = root
        .titled(title, ("sans-serif", 26))
        .map_err(|e| err(&e))?;
    let area = area
        .titled(
            subtitle,
            ("sans-serif", 16).into_font().color(&RGBColor(90, 90, 90)),
        )
        .map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&area)
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d((t0..t1).log_scale(), (e0..e1).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(if curves.iter().any(|c| c.config.ends_with("+denoise")) {
            "wall time of the renders, + denoising for the +denoise curves (s)"
        } else {
            "wall time of the renders (s)"
        })
        .y_desc("relMSE against the reference")
        .x_label_formatter(&|v| format!("{v:.1e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 18))
        .draw()
        .map_err(|e| err(&e))?;

    // A slope −1 guide through the middle of the data.
    let (tm, em) = ((t0 * t1).sqrt(), (e0 * e1).sqrt());
    let guide = [(t0, em * tm / t0), (t1, em * tm / t1)];
    chart
        .draw_series(DashedLineSeries::new(
            guide.iter().copied().filter(|p| p.1 >= e0 && p.1 <= e1),
            6,
            4,
            RGBColor(150, 150, 150).stroke_width(1),
        ))
        .map_err(|e| err(&e))?
        .label("slope −1 (unbiased)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(150, 150, 150)));

    for (i, c) in curves.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let pts: Vec<(f64, f64)> = c
            .steps
            .iter()
            .map(|s| (s.seconds, s.relmse))
            .filter(|(t, e)| *t > 0.0 && *e > 0.0)
            .collect();
        let slope = c
            .slope_time
            .map_or_else(|| "-".into(), |s| format!("{s:.2}"));
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(format!(
                "{}: slope {slope}, efficiency {:.2e}",
                c.config, c.efficiency
            ))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
