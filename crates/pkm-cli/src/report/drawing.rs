//! Orthographic drawings of a mechanism (top, front, side) as SVG, with plotters.

use anyhow::{anyhow, Result};
use pkm::mechanism::{LinkKind, PointRole, Skeleton};
use plotters::prelude::*;

/// One orthographic view: which coordinates go right and up.
#[derive(Clone, Copy)]
pub struct View {
    /// Title shown above the view.
    pub title: &'static str,
    /// Index (0 = X, 1 = Y, 2 = Z) of the horizontal axis.
    pub h: usize,
    /// Index of the vertical axis.
    pub v: usize,
}

/// Top (XY), front (XZ) and side (YZ) views.
pub const VIEWS: [View; 3] = [
    View {
        title: "Top view (X right, Y up)",
        h: 0,
        v: 1,
    },
    View {
        title: "Front view (X right, Z up)",
        h: 0,
        v: 2,
    },
    View {
        title: "Side view (Y right, Z up)",
        h: 1,
        v: 2,
    },
];

const AXES: [&str; 3] = ["X", "Y", "Z"];

fn link_style(kind: LinkKind) -> ShapeStyle {
    match kind {
        LinkKind::Strut => RGBColor(31, 119, 180).stroke_width(3),
        LinkKind::Base => RGBColor(60, 60, 60).stroke_width(2),
        LinkKind::Platform => RGBColor(44, 160, 44).stroke_width(2),
        LinkKind::Tool => RGBColor(214, 39, 40).stroke_width(4),
        LinkKind::Passive => RGBColor(150, 150, 150).stroke_width(3),
    }
}

fn point_color(role: PointRole) -> RGBColor {
    match role {
        PointRole::BaseJoint => RGBColor(60, 60, 60),
        PointRole::PlatformJoint => RGBColor(44, 160, 44),
        PointRole::PlatformCentre => RGBColor(44, 160, 44),
        PointRole::Tool => RGBColor(214, 39, 40),
        PointRole::Other => RGBColor(120, 120, 120),
    }
}

/// Draws `skeletons` (the first solid, the others as ghosts) in one view; returns SVG.
pub fn view_svg(skeletons: &[&Skeleton], view: View, size: (u32, u32)) -> Result<String> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for s in skeletons {
        for p in &s.points {
            for (k, axis) in [view.h, view.v].into_iter().enumerate() {
                lo[k] = lo[k].min(p.position[axis]);
                hi[k] = hi[k].max(p.position[axis]);
            }
        }
    }
    if !lo[0].is_finite() {
        return Err(anyhow!("nothing to draw"));
    }
    let (margin, xl, yl, cap) = (12u32, 32u32, 52u32, 28u32);
    let pw = (size.0 - 2 * margin - yl) as f64;
    let ph = (size.1 - 2 * margin - xl - cap) as f64;
    let span = [(hi[0] - lo[0]).max(1.0), (hi[1] - lo[1]).max(1.0)];
    // Equal scale on both axes (mm per pixel), with 12% padding.
    let scale = (span[0] / pw).max(span[1] / ph) * 1.24;
    let mid = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let xr = (mid[0] - scale * pw / 2.0)..(mid[0] + scale * pw / 2.0);
    let yr = (mid[1] - scale * ph / 2.0)..(mid[1] + scale * ph / 2.0);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(margin)
            .caption(view.title, ("sans-serif", 16))
            .x_label_area_size(xl)
            .y_label_area_size(yl)
            .build_cartesian_2d(xr, yr)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc(format!("{} [mm]", AXES[view.h]))
            .y_desc(format!("{} [mm]", AXES[view.v]))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        for (n, s) in skeletons.iter().enumerate().rev() {
            let ghost = n > 0;
            for l in &s.links {
                let a = &s.points[l.from].position;
                let b = &s.points[l.to].position;
                let mut style = link_style(l.kind);
                if ghost {
                    style = style.color.mix(0.25).stroke_width(style.stroke_width);
                }
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(a[view.h], a[view.v]), (b[view.h], b[view.v])],
                        style,
                    )))
                    .map_err(|e| anyhow!("{e}"))?;
            }
            if ghost {
                continue;
            }
            for p in &s.points {
                let c = point_color(p.role);
                let xy = (p.position[view.h], p.position[view.v]);
                let marker = EmptyElement::at(xy)
                    + Circle::new((0, 0), 4, c.filled())
                    + Text::new(
                        p.name.clone(),
                        (6, -16),
                        ("sans-serif", 14).into_font().color(&c),
                    );
                chart
                    .draw_series(std::iter::once(marker))
                    .map_err(|e| anyhow!("{e}"))?;
            }
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(out)
}
