//! The report's 3D view: an interactive three.js scene (orbit, zoom, pan) of the
//! machine at the report's pose, the workspace map's reachable points coloured by the
//! condition number, and the motion section's path as an animation with a time slider
//! and the actuator values. The workspace and motion sections leave their data in
//! [`Scene`]; the view is written where the `view3d` section stands once they ran.
//! The script (three.js and `web/src/view3d.js`) is bundled at build time
//! (`build.rs`) and inlined: the report stays one file that opens offline.

use anyhow::Result;
use pkm::analysis::motion::{Decimated, SampleRow, SampleSink};
use pkm::Machine;
use serde_json::json;

use super::html::Html;
use super::Context;

/// three.js and the scene code, minified (empty when the build had no npm).
const BUNDLE: &str = include_str!(env!("PKM_VIEW3D"));

/// Marks where the view goes until the sections that feed it have run.
pub const PLACEHOLDER: &str = "<!--pkm-view3d-->";

/// The most reachable points the cloud shows (a stride thins larger maps).
const MAX_CLOUD: usize = 15_000;

/// The most frames of the animation.
const MAX_FRAMES: usize = 240;

/// What the sections leave for the view (internal units).
#[derive(Default)]
pub struct Scene {
    /// Reachable tool positions (mm) and their condition numbers.
    pub cloud: Vec<([f64; 3], f64)>,
    /// Poses and actuator values along the path, with their times.
    pub frames: Frames,
}

/// A sink keeping at most [`MAX_FRAMES`] evenly spaced samples of a run
/// ([`Decimated`]): `(t, pose, actuators)`.
pub struct Frames(pub Decimated<(f64, Vec<f64>, Vec<f64>)>);

impl Default for Frames {
    fn default() -> Self {
        Frames(Decimated::new(MAX_FRAMES))
    }
}

impl SampleSink for Frames {
    fn sample(&mut self, s: &SampleRow) -> pkm::Result<()> {
        self.0.push(|| (s.t, s.x.to_vec(), s.q.to_vec()));
        Ok(())
    }
}

/// Whether this build has the 3D view.
pub fn available() -> bool {
    !BUNDLE.trim().is_empty()
}

/// The section's heading and the placeholder the view replaces.
pub fn section(h: &mut Html, _machine: &Machine, _ctx: &Context) -> Result<()> {
    h.h2_id("view3d", "3D view");
    h.raw(PLACEHOLDER);
    Ok(())
}

/// The view's HTML: the container, the scene as JSON and the bundled script; a note
/// when this build has no bundle.
pub fn html(machine: &Machine, ctx: &Context) -> Result<String> {
    if !available() {
        return Ok(
            "<p>This build of pkm has no 3D view: it was compiled without Node and npm \
                   (see the README).</p>"
                .into(),
        );
    }
    let sk = machine.mechanism().skeleton(&ctx.pose)?;
    let points: Vec<serde_json::Value> = sk
        .points
        .iter()
        .map(|p| {
            json!({"name": p.name, "role": format!("{:?}", p.role),
                   "p": [cm(p.position[0]), cm(p.position[1]), cm(p.position[2])]})
        })
        .collect();
    let links: Vec<serde_json::Value> = sk
        .links
        .iter()
        .map(|l| json!({"from": l.from, "to": l.to, "kind": format!("{:?}", l.kind)}))
        .collect();
    let scene = ctx.scene.borrow();
    let cloud = cloud_json(&scene.cloud);
    let motion = motion_json(machine, &scene.frames)?;
    let data =
        json!({"skeleton": {"points": points, "links": links}, "cloud": cloud, "motion": motion});
    // A JSON string may hold "</script>": escaped, it cannot close the element.
    let data = serde_json::to_string(&data)?.replace("</", "<\\/");
    let notes = [
        (!scene.cloud.is_empty()).then_some("the workspace map's reachable points, blue where the condition number is low, red where high"),
        (!scene.frames.0.is_empty()).then_some("the motion section's path, animated (play, or drag the time slider)"),
    ]
    .into_iter()
    .flatten()
    .collect::<Vec<_>>();
    Ok(format!(
        "<p>The machine at {}{}{}. Drag to orbit, scroll to zoom, right-drag to pan.</p>\n\
         <div id=\"pkm-view3d\"></div>\n\
         <script type=\"application/json\" id=\"pkm-scene\">{data}</script>\n\
         <script>{}</script>\n",
        ctx.pose_label,
        if notes.is_empty() { "" } else { "; " },
        notes.join("; "),
        BUNDLE.replace("</script", "<\\/script")
    ))
}

/// A coordinate (mm) rounded to 0.01 mm for the scene.
fn cm(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// The workspace map's reachable points (at most [`MAX_CLOUD`]) with their condition
/// numbers and its range; null without a map.
fn cloud_json(cloud: &[([f64; 3], f64)]) -> serde_json::Value {
    if cloud.is_empty() {
        return serde_json::Value::Null;
    }
    let stride = cloud.len().div_ceil(MAX_CLOUD);
    let kept: Vec<&([f64; 3], f64)> = cloud.iter().step_by(stride).collect();
    let (lo, hi) = kept.iter().fold((f64::INFINITY, 0.0f64), |(a, b), c| {
        (a.min(c.1), b.max(c.1))
    });
    json!({
        "points": kept.iter().flat_map(|c| c.0.map(cm)).collect::<Vec<f64>>(),
        "condition": kept.iter().map(|c| (c.1 * 1000.0).round() / 1000.0).collect::<Vec<f64>>(),
        "min": lo, "max": hi,
    })
}

/// The animation: per frame the skeleton's point positions, the tool path, the
/// actuator values in user units.
fn motion_json(machine: &Machine, frames: &Frames) -> Result<serde_json::Value> {
    if frames.0.is_empty() {
        return Ok(serde_json::Value::Null);
    }
    let m = machine.mechanism();
    let r = |v: f64| (v * 100.0).round() / 100.0;
    let mut flat = Vec::new();
    let mut path = Vec::new();
    for (_, x, _) in frames.0.iter() {
        let sk = m.skeleton(x)?;
        flat.push(
            sk.points
                .iter()
                .flat_map(|p| [r(p.position[0]), r(p.position[1]), r(p.position[2])])
                .collect::<Vec<f64>>(),
        );
        if let Some(t) = sk
            .points
            .iter()
            .find(|p| p.role == pkm::mechanism::PointRole::Tool)
        {
            path.push([r(t.position[0]), r(t.position[1]), r(t.position[2])]);
        }
    }
    let actuators: Vec<serde_json::Value> = m
        .actuators()
        .iter()
        .enumerate()
        .map(|(i, a)| {
            json!({"name": a.name, "unit": a.quantity.unit(),
                   "values": frames.0.iter().map(|f| (a.quantity.to_user(f.2[i]) * 1e4).round() / 1e4).collect::<Vec<f64>>()})
        })
        .collect();
    Ok(json!({
        "t": frames.0.iter().map(|f| (f.0 * 1e4).round() / 1e4).collect::<Vec<f64>>(),
        "frames": flat,
        "path": path,
        "actuators": actuators,
    }))
}
