//! Time-series plots (SVG, plotters), in the manner of seed 000's fig. 6.

use anyhow::{anyhow, Result};
use plotters::prelude::*;

/// One curve: name and (t, value) points.
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Stacked panels sharing the time axis; each panel is (title, y label, curves).
pub fn panels_svg(
    title: &str,
    panels: &[(String, String, Vec<Series>)],
    size: (u32, u32),
) -> Result<String> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let root = root
            .titled(title, ("sans-serif", 18))
            .map_err(|e| anyhow!("{e}"))?;
        let areas = root.split_evenly((panels.len(), 1));
        for (area, (ptitle, ylabel, series)) in areas.iter().zip(panels) {
            let (mut t0, mut t1, mut y0, mut y1) = (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            );
            for s in series {
                for &(t, y) in &s.points {
                    t0 = t0.min(t);
                    t1 = t1.max(t);
                    y0 = y0.min(y);
                    y1 = y1.max(y);
                }
            }
            if !t0.is_finite() {
                continue;
            }
            if t1 - t0 < 1e-12 {
                t1 = t0 + 1.0;
            }
            // Plotters needs a range that is not too narrow for its tick marks.
            let pad = ((y1 - y0) * 0.08).max(1e-3 * y0.abs().max(y1.abs()).max(1.0));
            let (y0, y1) = (y0 - pad, y1 + pad);
            let mut chart = ChartBuilder::on(area)
                .margin(8)
                .caption(ptitle, ("sans-serif", 14))
                .x_label_area_size(30)
                .y_label_area_size(64)
                .build_cartesian_2d(t0..t1, y0..y1)
                .map_err(|e| anyhow!("{e}"))?;
            chart
                .configure_mesh()
                .x_desc("t [s]")
                .y_desc(ylabel.as_str())
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
            for (i, s) in series.iter().enumerate() {
                let c = COLORS[i % COLORS.len()];
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                    .map_err(|e| anyhow!("{e}"))?
                    .label(s.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(RGBColor(200, 200, 200))
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(out)
}
