//! Time-series plots (SVG, plotters), in the manner of seed 000's fig. 6.

use anyhow::{anyhow, Result};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::ticks::tick;

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

/// Stacked panels sharing the x axis `xlabel`; each panel is (title, y label, curves).
pub fn panels_svg_x(
    title: &str,
    xlabel: &str,
    panels: &[(String, String, Vec<Series>)],
    size: (u32, u32),
) -> Result<String> {
    panels_svg_span(title, xlabel, None, panels, size)
}

/// [`panels_svg_x`] over the x span `span` when given (where the curves have no
/// points, the plot stays empty: a quantity undefined there shows as a gap), else the
/// curves' own.
pub fn panels_svg_span(
    title: &str,
    xlabel: &str,
    span: Option<(f64, f64)>,
    panels: &[(String, String, Vec<Series>)],
    size: (u32, u32),
) -> Result<String> {
    let panels: Vec<Panel> = panels
        .iter()
        .map(|(t, y, s)| Panel {
            title: t.as_str(),
            ylabel: y.as_str(),
            series: s.as_slice(),
            limits: Vec::new(),
        })
        .collect();
    panels_marked(title, xlabel, span, &panels, &[], size)
}

/// One panel of [`panels_marked`]: title, y label, curves, and horizontal limit lines
/// (value, name).
pub struct Panel<'a> {
    pub title: &'a str,
    pub ylabel: &'a str,
    pub series: &'a [Series],
    pub limits: Vec<(f64, String)>,
}

/// Width of the legend strip right of each panel (px).
const LEGEND_W: u32 = 120;

/// A panel's chart.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A drawing area of the plot.
type Area<'b> = DrawingArea<SVGBackend<'b>, plotters::coord::Shift>;

/// Grey of the segment marks.
const GREY: RGBColor = RGBColor(170, 170, 170);

/// Red of the limit lines.
const RED: RGBColor = RGBColor(198, 40, 40);

/// Stacked panels sharing the x axis, each with its legend in a strip to its right
/// (never over the curves), its limits as dashed red lines (drawn when within half the
/// curves' span of them: a limit far away would flatten the curves), and `marks`
/// (x, label) as thin vertical lines through every panel (G-code segment starts;
/// labelled when there are at most 12).
pub fn panels_marked(
    title: &str,
    xlabel: &str,
    span: Option<(f64, f64)>,
    panels: &[Panel],
    marks: &[(f64, String)],
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
        for (area, p) in areas.iter().zip(panels) {
            draw_panel(area, p, xlabel, span, marks)?;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(out)
}

/// One panel of [`panels_marked`] in `area`: the chart, and its legend right of it.
fn draw_panel(
    area: &Area,
    p: &Panel,
    xlabel: &str,
    span: Option<(f64, f64)>,
    marks: &[(f64, String)],
) -> Result<()> {
    let (w, _) = area.dim_in_pixel();
    let (plot_area, legend_area) = area.split_horizontally(w.saturating_sub(LEGEND_W));
    let Some((t0, t1, mut y0, mut y1)) = extent(p, span) else {
        return Ok(());
    };
    let reach = 0.5 * (y1 - y0).max(1e-9 * y0.abs().max(y1.abs()).max(1.0));
    let limits: Vec<&(f64, String)> = p
        .limits
        .iter()
        .filter(|(v, _)| v.is_finite() && *v >= y0 - reach && *v <= y1 + reach)
        .collect();
    for (v, _) in &limits {
        y0 = y0.min(*v);
        y1 = y1.max(*v);
    }
    // Plotters needs a range that is not too narrow for its tick marks.
    let pad = ((y1 - y0) * 0.08).max(1e-3 * y0.abs().max(y1.abs()).max(1.0));
    let (y0, y1) = (y0 - pad, y1 + pad);
    if !(y0.is_finite() && y1.is_finite() && (y1 - y0).is_finite()) {
        return Ok(());
    }
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(8)
        .caption(p.title, ("sans-serif", 14))
        .x_label_area_size(30)
        .y_label_area_size(64)
        .build_cartesian_2d(t0..t1, y0..y1)
        .map_err(|e| anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_desc(p.ylabel)
        .x_label_formatter(&|v| tick(*v, t1 - t0))
        .y_label_formatter(&|v| tick(*v, y1 - y0))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    draw_marks(&mut chart, marks, (t0, t1), (y0, y1))?;
    for (v, _) in &limits {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(t0, *v), (t1, *v)],
                6,
                4,
                RED.stroke_width(1),
            ))
            .map_err(|e| anyhow!("{e}"))?;
    }
    for (i, s) in p.series.iter().enumerate() {
        let c = COLORS[i % COLORS.len()];
        for run in finite_runs(&s.points) {
            chart
                .draw_series(LineSeries::new(run.iter().copied(), c.stroke_width(2)))
                .map_err(|e| anyhow!("{e}"))?;
        }
    }
    draw_legend(&legend_area, p, !limits.is_empty(), !marks.is_empty())
}

/// The stretches of `points` between the points that are not finite: a curve is drawn
/// with a gap where its quantity is undefined.
fn finite_runs(points: &[(f64, f64)]) -> impl Iterator<Item = &[(f64, f64)]> {
    points
        .split(|(t, y)| !(t.is_finite() && y.is_finite()))
        .filter(|run| !run.is_empty())
}

/// The x and y ranges of a panel's curves, x over `span` when given (at least 1e-12
/// wide); `None` without an x range.
fn extent(p: &Panel, span: Option<(f64, f64)>) -> Option<(f64, f64, f64, f64)> {
    let (mut t0, mut t1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    // A point that is not finite (an undefined quantity, an overflow) is no part of
    // the range: it is left out of the curve too (`finite_runs`).
    for s in p.series {
        for &(t, y) in s
            .points
            .iter()
            .filter(|(t, y)| t.is_finite() && y.is_finite())
        {
            t0 = t0.min(t);
            t1 = t1.max(t);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    if let Some((a, b)) = span {
        (t0, t1) = (a, b);
    }
    // A range whose width overflows (curves from -1e300 to 1e300) cannot be drawn.
    if !(t0.is_finite() && (t1 - t0).is_finite() && (y1 - y0).is_finite()) {
        return None;
    }
    if t1 - t0 < 1e-12 {
        t1 = t0 + 1.0;
    }
    Some((t0, t1, y0, y1))
}

/// The marks within the x range `t` as vertical lines, labelled when at most 12.
fn draw_marks(
    chart: &mut Chart,
    marks: &[(f64, String)],
    (t0, t1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<()> {
    for (x, label) in marks.iter().filter(|m| m.0 >= t0 && m.0 <= t1) {
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(*x, y0), (*x, y1)],
                GREY.stroke_width(1),
            )))
            .map_err(|e| anyhow!("{e}"))?;
        if marks.len() <= 12 {
            chart
                .draw_series(std::iter::once(Text::new(
                    label.clone(),
                    (*x, y1),
                    ("sans-serif", 10).into_font().color(&GREY),
                )))
                .map_err(|e| anyhow!("{e}"))?;
        }
    }
    Ok(())
}

/// The legend of a panel, in its own strip: the curves, then the limit and the marks
/// when drawn.
fn draw_legend(legend_area: &Area, p: &Panel, limits: bool, marks: bool) -> Result<()> {
    let mut entries: Vec<(String, ShapeStyle)> = p
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| (s.name.clone(), COLORS[i % COLORS.len()].stroke_width(2)))
        .collect();
    if limits {
        entries.push(("limit".into(), RED.stroke_width(1)));
    }
    if marks {
        entries.push(("segment start".into(), GREY.stroke_width(1)));
    }
    for (k, (name, style)) in entries.iter().enumerate() {
        let y = 34 + 16 * k as i32;
        legend_area
            .draw(&PathElement::new(vec![(4, y), (22, y)], *style))
            .map_err(|e| anyhow!("{e}"))?;
        legend_area
            .draw(&Text::new(
                name.clone(),
                (27, y - 7),
                ("sans-serif", 12).into_font(),
            ))
            .map_err(|e| anyhow!("{e}"))?;
    }
    Ok(())
}

/// Horizontal bar chart (largest first, as given): labels and values.
pub fn bars_svg(title: &str, xlabel: &str, items: &[(String, f64)], width: u32) -> Result<String> {
    let n = items.len().max(1);
    let height = 80 + 22 * n as u32;
    let vmax = items.iter().map(|i| i.1).fold(0.0, f64::max);
    let vmax = if vmax > 0.0 { vmax * 1.05 } else { 1.0 };
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(10)
            .caption(title, ("sans-serif", 15))
            .x_label_area_size(32)
            .y_label_area_size(200)
            .build_cartesian_2d(0.0..vmax, 0.0..n as f64)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .disable_y_axis()
            .x_desc(xlabel)
            .x_label_formatter(&|v| tick(*v, vmax))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        // Labels beside their bars, right-aligned in the label area.
        let style = TextStyle::from(("sans-serif", 12).into_font()).pos(
            plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Right,
                plotters::style::text_anchor::VPos::Center,
            ),
        );
        for (k, (label, _)) in items.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(0.0, (n - 1 - k) as f64 + 0.5));
            root.draw(&Text::new(label.clone(), (px - 6, py), style.clone()))
                .map_err(|e| anyhow!("{e}"))?;
        }
        chart
            .draw_series(items.iter().enumerate().map(|(k, (_, v))| {
                let y = (n - 1 - k) as f64;
                Rectangle::new([(0.0, y + 0.15), (*v, y + 0.85)], COLORS[0].filled())
            }))
            .map_err(|e| anyhow!("{e}"))?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(out)
}

/// Histogram from `(lower edge, count)` bins of equal width.
pub fn histogram_svg(
    title: &str,
    xlabel: &str,
    bins: &[(f64, usize)],
    size: (u32, u32),
) -> Result<String> {
    let w = if bins.len() > 1 {
        bins[1].0 - bins[0].0
    } else {
        1.0
    };
    let w = if w > 0.0 { w } else { 1.0 };
    // From 0 for norms; from the first bin for signed values (errors along a direction).
    let x0 = bins.first().map_or(0.0, |b| b.0.min(0.0));
    let x1 = bins.last().map(|b| b.0 + w).unwrap_or(1.0);
    let cmax = bins.iter().map(|b| b.1).max().unwrap_or(1).max(1) as f64 * 1.05;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(10)
            .caption(title, ("sans-serif", 15))
            .x_label_area_size(32)
            .y_label_area_size(56)
            .build_cartesian_2d(x0..x1, 0.0..cmax)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc(xlabel)
            .y_desc("samples")
            .x_label_formatter(&|v| tick(*v, x1 - x0))
            .y_label_formatter(&|v| tick(*v, cmax))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(
                bins.iter().map(|(x, c)| {
                    Rectangle::new([(*x, 0.0), (*x + w, *c as f64)], COLORS[0].filled())
                }),
            )
            .map_err(|e| anyhow!("{e}"))?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panel(points: Vec<(f64, f64)>) -> Vec<(String, String, Vec<Series>)> {
        let series = vec![Series {
            name: "q".into(),
            points,
        }];
        vec![("title".into(), "y".into(), series)]
    }

    /// Values that are not finite, or whose range overflows, give a plot with a gap or
    /// an empty panel, never plotters' assertion on a NaN range.
    #[test]
    fn values_that_are_not_finite_make_no_panic() {
        let cases = [
            vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)],
            vec![(0.0, f64::INFINITY), (1.0, f64::NEG_INFINITY)],
            vec![(f64::NAN, 1.0), (1.0, 2.0)],
            vec![(0.0, -1e300), (1.0, 1e300)],
            vec![(0.0, -1.7e308), (1.0, 0.0)],
            vec![(0.0, f64::NAN)],
        ];
        for points in cases {
            let svg = panels_svg_x("t", "x", &panel(points.clone()), (400, 300));
            assert!(svg.is_ok(), "{points:?}: {svg:?}");
        }
        let span = Some((0.0, 1.0));
        let svg = panels_svg_span("t", "x", span, &panel(Vec::new()), (400, 300));
        assert!(svg.is_ok());
    }

    #[test]
    fn a_gap_splits_a_curve() {
        let pts = [(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0), (3.0, 4.0)];
        let runs: Vec<_> = finite_runs(&pts).collect();
        assert_eq!(runs, [&pts[..1], &pts[2..]]);
    }
}
