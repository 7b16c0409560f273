//! Heat maps of a 2D workspace slice (SVG, plotters): a value (condition number,
//! actuator position or rate, pose coordinate) over the reachable cells, grey where a
//! limit binds.

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use super::ticks::{linear_ticks, log_ticks, tick};

/// One cell: centre (h, v) in user units, and the condition number (None: unreachable).
pub struct Cell {
    /// Horizontal coordinate.
    pub h: f64,
    /// Vertical coordinate.
    pub v: f64,
    /// The value when reachable.
    pub value: Option<f64>,
}

fn color(t: f64) -> RGBColor {
    // Viridis-like ramp from dark blue (well conditioned) to yellow (poor).
    let stops = [
        (68, 1, 84),
        (59, 82, 139),
        (33, 145, 140),
        (94, 201, 98),
        (253, 231, 37),
    ];
    let t = t.clamp(0.0, 1.0) * (stops.len() - 1) as f64;
    let i = (t.floor() as usize).min(stops.len() - 2);
    let f = t - i as f64;
    let lerp = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * f).round() as u8;
    RGBColor(
        lerp(stops[i].0, stops[i + 1].0),
        lerp(stops[i].1, stops[i + 1].1),
        lerp(stops[i].2, stops[i + 1].2),
    )
}

/// How values map to colours.
#[derive(Clone, Copy)]
pub enum Scale<'a> {
    /// Colour by log10 of the value (condition numbers); the label names the value.
    Log10(&'a str),
    /// Colour by the value itself.
    Linear(&'a str),
}

/// A drawing area of the heat map.
type Area<'b> = DrawingArea<SVGBackend<'b>, plotters::coord::Shift>;

/// The span of a slice: its cells' extent (h, v) and the range of the coloured
/// quantity.
struct Extent {
    h: (f64, f64),
    v: (f64, f64),
    /// Range of the coloured quantity (finite and not too narrow for plotters' ticks).
    c: (f64, f64),
}

impl Extent {
    /// The extent of `cells` (`dh`, `dv` the cell sizes), coloured by `tf` of the
    /// value; `None` without cells.
    fn of(cells: &[Cell], dh: f64, dv: f64, tf: fn(f64) -> f64) -> Option<Extent> {
        let (mut h0, mut h1, mut v0, mut v1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        let (mut c0, mut c1) = (f64::INFINITY, f64::NEG_INFINITY);
        for c in cells {
            h0 = h0.min(c.h - dh / 2.0);
            h1 = h1.max(c.h + dh / 2.0);
            v0 = v0.min(c.v - dv / 2.0);
            v1 = v1.max(c.v + dv / 2.0);
            if let Some(x) = c.value.map(tf).filter(|v| v.is_finite()) {
                c0 = c0.min(x);
                c1 = c1.max(x);
            }
        }
        if !h0.is_finite() {
            return None;
        }
        // Plotters needs a finite, not too narrow range for its tick marks.
        if !c0.is_finite() || !c1.is_finite() {
            c0 = 0.0;
            c1 = 1.0;
        }
        let min_span = 0.01 * c0.abs().max(c1.abs()).max(1.0);
        if c1 - c0 < min_span {
            let mid = 0.5 * (c0 + c1);
            c0 = mid - 0.5 * min_span;
            c1 = mid + 0.5 * min_span;
        }
        Some(Extent {
            h: (h0, h1),
            v: (v0, v1),
            c: (c0, c1),
        })
    }
}

/// Draws the slice; `dh`, `dv` are the cell sizes.
#[allow(clippy::too_many_arguments)]
pub fn slice_svg(
    title: &str,
    hlabel: &str,
    vlabel: &str,
    scale: Scale,
    cells: &[Cell],
    dh: f64,
    dv: f64,
    size: (u32, u32),
) -> Result<String> {
    let (tf, bar_label): (fn(f64) -> f64, String) = match scale {
        Scale::Log10(l) => (f64::log10, format!("{l} (log scale)")),
        Scale::Linear(l) => (|x| x, l.to_string()),
    };
    let ext = Extent::of(cells, dh, dv, tf).ok_or_else(|| anyhow!("empty slice"))?;
    let ((h0, h1), (v0, v1), (c0, c1)) = (ext.h, ext.v, ext.c);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let (main, bar) = root.split_horizontally(size.0 - 100);
        let mut chart = ChartBuilder::on(&main)
            .margin(10)
            .caption(title, ("sans-serif", 15))
            .x_label_area_size(32)
            .y_label_area_size(56)
            .build_cartesian_2d(h0..h1, v0..v1)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(hlabel)
            .y_desc(vlabel)
            .x_label_formatter(&|v| tick(*v, h1 - h0))
            .y_label_formatter(&|v| tick(*v, v1 - v0))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .draw_series(cells.iter().map(|c| {
                let fill = match c.value.map(tf).filter(|v| v.is_finite()) {
                    Some(x) => color((x - c0) / (c1 - c0)).filled(),
                    None => RGBColor(225, 225, 225).filled(),
                };
                Rectangle::new(
                    [
                        (c.h - dh / 2.0, c.v - dv / 2.0),
                        (c.h + dh / 2.0, c.v + dv / 2.0),
                    ],
                    fill,
                )
            }))
            .map_err(|e| anyhow!("{e}"))?;
        colour_bar(&bar, scale, (c0, c1), &bar_label)?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(out)
}

/// Colour bar, in the coloured quantity `c` (log10 of the value on a log scale), its
/// ticks at round values of the value itself.
fn colour_bar(bar: &Area, scale: Scale, (c0, c1): (f64, f64), bar_label: &str) -> Result<()> {
    let log = matches!(scale, Scale::Log10(_));
    let ticks = if log {
        log_ticks(c0, c1)
    } else {
        linear_ticks(c0, c1, 6)
    };
    let label_of = |v: f64| {
        if log {
            tick(10f64.powf(v), 10f64.powf(v))
        } else {
            tick(v, c1 - c0)
        }
    };
    let mut cb = ChartBuilder::on(bar)
        .margin_top(40)
        .margin_bottom(42)
        .margin_right(8)
        .y_label_area_size(58)
        .build_cartesian_2d(
            0.0..1.0,
            TickedAxis {
                range: c0..c1,
                ticks,
            },
        )
        .map_err(|e| anyhow!("{e}"))?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_label_style(("sans-serif", 11))
        .axis_desc_style(("sans-serif", 12))
        .y_label_formatter(&|v| label_of(*v))
        .y_desc(bar_label)
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    let n = 60;
    cb.draw_series((0..n).map(|i| {
        let a = c0 + (c1 - c0) * i as f64 / n as f64;
        let b = c0 + (c1 - c0) * (i + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            color(i as f64 / (n - 1) as f64).filled(),
        )
    }))
    .map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

/// A linear axis with its ticks where given (plotters' `WithKeyPoints` has no label
/// formatter, which a mesh needs).
struct TickedAxis {
    range: std::ops::Range<f64>,
    ticks: Vec<f64>,
}

impl Ranged for TickedAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let t = (value - self.range.start) / (self.range.end - self.range.start);
        limit.0 + (t * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, _: Hint) -> Vec<f64> {
        self.ticks.clone()
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.range.clone()
    }
}
