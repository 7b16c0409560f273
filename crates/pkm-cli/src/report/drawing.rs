//! Orthographic drawings of a mechanism (top, front, side) as SVG, with plotters.

use anyhow::{anyhow, Result};
use pkm::mechanism::{LinkKind, PointRole, Skeleton};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::ticks::tick;

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

/// The views a skeleton needs: the one plane it lies in when it is planar (one
/// coordinate the same for every point), else the top, front and side views.
pub fn views_for(sk: &Skeleton) -> Vec<View> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &sk.points {
        for k in 0..3 {
            lo[k] = lo[k].min(p.position[k]);
            hi[k] = hi[k].max(p.position[k]);
        }
    }
    let ext: Vec<f64> = (0..3).map(|k| hi[k] - lo[k]).collect();
    let big = ext.iter().copied().fold(0.0, f64::max);
    match (0..3).find(|&k| ext[k] <= 1e-9 * big.max(1.0)) {
        Some(flat) if sk.points.len() > 1 => {
            let (h, v) = match flat {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            vec![View {
                title: PLANE_TITLES[flat],
                h,
                v,
            }]
        }
        _ => VIEWS.to_vec(),
    }
}

/// Titles of the view of a mechanism lying in the plane normal to X, Y or Z.
const PLANE_TITLES: [&str; 3] = [
    "In its plane (Y right, Z up)",
    "In its plane (X right, Z up)",
    "In its plane (X right, Y up)",
];

/// A view's chart: millimetres both ways.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A view's drawing area.
type Area<'b> = DrawingArea<SVGBackend<'b>, plotters::coord::Shift>;

/// The pixel layout of a view: its size, the margin, the areas of the axis labels, the
/// caption and the note of unlabelled points.
struct Layout {
    size: (u32, u32),
    margin: u32,
    /// Height of the x axis' label area.
    xl: u32,
    /// Width of the y axis' label area.
    yl: u32,
    /// Height of the caption.
    cap: u32,
    /// A strip below the x axis' label holds the note of unlabelled points.
    note: u32,
}

impl Layout {
    fn new(size: (u32, u32)) -> Layout {
        Layout {
            size,
            margin: 12,
            xl: 32,
            yl: 52,
            cap: 28,
            note: 14,
        }
    }

    /// Width and height of the plot (px).
    fn plot_size(&self) -> (f64, f64) {
        let pw = (self.size.0 - 2 * self.margin - self.yl) as f64;
        let ph = (self.size.1 - 2 * self.margin - self.xl - self.cap - self.note) as f64;
        (pw, ph)
    }

    /// The plot's box in pixels: left, top, right, bottom.
    fn plot_box(&self) -> [i32; 4] {
        let (margin, size) = (self.margin as i32, self.size);
        [
            margin + self.yl as i32,
            margin + self.cap as i32,
            size.0 as i32 - margin,
            size.1 as i32 - margin - self.note as i32 - self.xl as i32,
        ]
    }
}

/// The smallest and largest horizontal and vertical coordinates of the points in
/// `view`; `None` without points.
fn extent(skeletons: &[&Skeleton], view: View) -> Option<([f64; 2], [f64; 2])> {
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
    lo[0].is_finite().then_some((lo, hi))
}

/// Draws `skeletons` (the first solid, the others as ghosts) in one view; returns SVG.
pub fn view_svg(skeletons: &[&Skeleton], view: View, size: (u32, u32)) -> Result<String> {
    let (lo, hi) = extent(skeletons, view).ok_or_else(|| anyhow!("nothing to draw"))?;
    let lay = Layout::new(size);
    let (pw, ph) = lay.plot_size();
    let span = [(hi[0] - lo[0]).max(1.0), (hi[1] - lo[1]).max(1.0)];
    // Equal scale on both axes (mm per pixel), with 12% padding.
    let scale = (span[0] / pw).max(span[1] / ph) * 1.24;
    let mid = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let xr = (mid[0] - scale * pw / 2.0)..(mid[0] + scale * pw / 2.0);
    let yr = (mid[1] - scale * ph / 2.0)..(mid[1] + scale * ph / 2.0);
    let mut out = String::new();
    let mut unlabelled: Vec<String> = Vec::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(lay.margin)
            .margin_bottom(lay.margin + lay.note)
            .caption(view.title, ("sans-serif", 16))
            .x_label_area_size(lay.xl)
            .y_label_area_size(lay.yl)
            .build_cartesian_2d(xr.clone(), yr.clone())
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc(format!("{} [mm]", AXES[view.h]))
            .y_desc(format!("{} [mm]", AXES[view.v]))
            .light_line_style(RGBColor(235, 235, 235))
            .x_labels(5)
            .y_labels(6)
            .x_label_formatter(&|v| tick(*v, xr.end - xr.start))
            .y_label_formatter(&|v| tick(*v, yr.end - yr.start))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        for (n, s) in skeletons.iter().enumerate().rev() {
            let ghost = n > 0;
            draw_links(&mut chart, s, view, ghost)?;
            if ghost {
                continue;
            }
            draw_points(&mut chart, s, view)?;
            unlabelled.extend(draw_labels(&root, &chart, s, view, &lay)?);
        }
        if !unlabelled.is_empty() {
            draw_unlabelled(&root, &unlabelled, &lay)?;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(out)
}

/// The links of a skeleton, faint for a ghost.
fn draw_links(chart: &mut Chart, s: &Skeleton, view: View, ghost: bool) -> Result<()> {
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
    Ok(())
}

/// The points of a skeleton, coloured by their role.
fn draw_points(chart: &mut Chart, s: &Skeleton, view: View) -> Result<()> {
    for p in &s.points {
        let c = point_color(p.role);
        let xy = (p.position[view.h], p.position[view.v]);
        chart
            .draw_series(std::iter::once(Circle::new(xy, 4, c.filled())))
            .map_err(|e| anyhow!("{e}"))?;
    }
    Ok(())
}

/// Labels: points that fall on one spot in this view share one label; each label
/// takes the first place around its point that overlaps no label or point drawn
/// before; a label with no free place goes to the legend. Returns those labels.
fn draw_labels(
    root: &Area,
    chart: &Chart,
    s: &Skeleton,
    view: View,
    lay: &Layout,
) -> Result<Vec<String>> {
    let px: Vec<(i32, i32)> = s
        .points
        .iter()
        .map(|p| chart.backend_coord(&(p.position[view.h], p.position[view.v])))
        .collect();
    let mut taken: Vec<[i32; 4]> = px
        .iter()
        .map(|q| [q.0 - 4, q.1 - 4, q.0 + 4, q.1 + 4])
        .collect();
    let plot = lay.plot_box();
    let mut unlabelled = Vec::new();
    for SameSpot { members, at: q } in &same_spot_groups(&px) {
        let text = members
            .iter()
            .map(|&i| s.points[i].name.as_str())
            .collect::<Vec<_>>()
            .join("/");
        let w = (text.chars().count() as f64 * 7.2).ceil() as i32;
        let c = point_color(s.points[members[0]].role);
        match free_spot(*q, w, plot, &taken) {
            Some(b) => {
                taken.push(b);
                root.draw(&Text::new(
                    text,
                    (b[0], b[1]),
                    ("sans-serif", 13).into_font().color(&c),
                ))
                .map_err(|e| anyhow!("{e}"))?;
            }
            None => unlabelled.push(text),
        }
    }
    Ok(unlabelled)
}

/// Points that fall on one spot of a view: they share a label.
struct SameSpot {
    /// The points, by index.
    members: Vec<usize>,
    /// The pixel of the first.
    at: (i32, i32),
}

/// The points grouped by spot: within 3 px of a group's first point.
fn same_spot_groups(px: &[(i32, i32)]) -> Vec<SameSpot> {
    let mut groups: Vec<SameSpot> = Vec::new();
    for (i, q) in px.iter().enumerate() {
        match groups
            .iter_mut()
            .find(|g| (g.at.0 - q.0).abs() <= 3 && (g.at.1 - q.1).abs() <= 3)
        {
            Some(g) => g.members.push(i),
            None => groups.push(SameSpot {
                members: vec![i],
                at: *q,
            }),
        }
    }
    groups
}

/// The first box of a label `w` px wide around the point at `q` that lies in `plot`
/// and overlaps nothing `taken`.
fn free_spot(q: (i32, i32), w: i32, plot: [i32; 4], taken: &[[i32; 4]]) -> Option<[i32; 4]> {
    let hgt = 14;
    [
        (6, -16),
        (6, 3),
        (-w - 6, -16),
        (-w - 6, 3),
        (-w / 2, -22),
        (-w / 2, 8),
        (10, -6),
        (-w - 10, -6),
    ]
    .into_iter()
    .map(|(dx, dy)| [q.0 + dx, q.1 + dy, q.0 + dx + w, q.1 + dy + hgt])
    .find(|b| {
        b[0] >= plot[0]
            && b[1] >= plot[1]
            && b[2] <= plot[2]
            && b[3] <= plot[3]
            && taken
                .iter()
                .all(|t| b[2] <= t[0] || t[2] <= b[0] || b[3] <= t[1] || t[3] <= b[1])
    })
}

/// The note of the labels with no free place, in the strip below the plot.
fn draw_unlabelled(root: &Area, unlabelled: &[String], lay: &Layout) -> Result<()> {
    let mut line = format!("not labelled (crowded): {}", unlabelled.join(", "));
    if line.chars().count() > 64 {
        line = line.chars().take(61).collect::<String>() + "...";
    }
    root.draw(&Text::new(
        line,
        (
            lay.margin as i32,
            (lay.size.1 - lay.margin - lay.note + 2) as i32,
        ),
        ("sans-serif", 11)
            .into_font()
            .color(&RGBColor(110, 110, 110)),
    ))
    .map_err(|e| anyhow!("{e}"))?;
    Ok(())
}
