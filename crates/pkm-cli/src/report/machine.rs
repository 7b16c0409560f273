//! The fixed sections of the report: the machine (coordinates, actuators, limits), its
//! drawing at the report's pose, and the kinematic checks.

use anyhow::Result;
use pkm::verify::{machine_check_table, CheckRow};
use pkm::Machine;

use super::html::{esc, Html};
use super::{drawing, mark, Context};
use crate::poses::Shown;

/// Tolerances the check table is judged by.
const ROUND_TRIP_TOL_MM: f64 = 1e-9;
const ROUND_TRIP_TOL_RAD: f64 = 1e-9;
const JACOBIAN_TOL: f64 = 1e-6;

/// The machine's pose coordinates and actuators with their limits and home values.
pub fn summary(h: &mut Html, machine: &Machine, _ctx: &Context) -> Result<()> {
    let m = machine.mechanism();
    h.h2_id("machine", "Machine");
    let driven = m.driven();
    let mut rows = Vec::new();
    let home = m.home();
    for (i, c) in m.coordinates().iter().enumerate() {
        rows.push(vec![
            esc(&c.name),
            c.quantity.unit().into(),
            if driven.contains(&i) {
                "driven by the actuators".into()
            } else {
                "held by the mechanism".into()
            },
            format!("{:.4}", Shown(c.quantity.to_user(home[i]))),
        ]);
    }
    h.table(&["pose coordinate", "unit", "role", "home"], &rows);
    let q_home = m.inverse(&home).ok();
    let rows: Vec<Vec<String>> = m
        .actuators()
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let u = |v: f64| x.quantity.to_user(v);
            let unit = x.quantity.unit();
            vec![
                esc(&x.name),
                unit.into(),
                format!("{:.3}", u(x.range.min)),
                format!("{:.3}", u(x.range.max)),
                x.max_velocity
                    .map(|v| format!("{:.1} {unit}/s", u(v)))
                    .unwrap_or_else(|| "-".into()),
                x.max_acceleration
                    .map(|v| format!("{:.1} {unit}/s²", u(v)))
                    .unwrap_or_else(|| "-".into()),
                q_home
                    .as_ref()
                    .map(|q| format!("{:.4}", Shown(u(q[i]))))
                    .unwrap_or_else(|| "no solution".into()),
            ]
        })
        .collect();
    h.table(
        &[
            "actuator",
            "unit",
            "min",
            "max",
            "max velocity",
            "max acceleration",
            "at home",
        ],
        &rows,
    );

    Ok(())
}

/// The mechanism at the report's pose (home faint when they differ), three views, and
/// its joint coordinates.
pub fn drawing_section(h: &mut Html, machine: &Machine, ctx: &Context) -> Result<()> {
    let m = machine.mechanism();
    h.h2_id("drawing", &format!("Drawing at {}", ctx.pose_label));
    let sk = m.skeleton(&ctx.pose)?;
    let home_sk = m.skeleton(&m.home())?;
    let with_home = ctx.pose != m.home();
    let mut svgs = String::new();
    for v in drawing::views_for(&sk) {
        let sks: Vec<&pkm::mechanism::Skeleton> = if with_home {
            vec![&sk, &home_sk]
        } else {
            vec![&sk]
        };
        svgs.push_str(&drawing::view_svg(&sks, v, (400, 400))?);
    }
    h.raw(&format!("<div class=\"views\">{svgs}</div>"));
    let rows: Vec<Vec<String>> = sk
        .points
        .iter()
        .map(|p| {
            vec![
                esc(&p.name),
                format!("{:?}", p.role),
                format!("{:.4}", Shown(p.position[0])),
                format!("{:.4}", Shown(p.position[1])),
                format!("{:.4}", Shown(p.position[2])),
            ]
        })
        .collect();
    h.details(
        "Joint coordinates at home (base frame, mm)",
        &Html::table_string(&["point", "role", "X", "Y", "Z"], &rows),
    );

    Ok(())
}

/// Inverse and forward kinematics, limits, Jacobian and conditioning at home and at
/// steps of 20 mm and 5 deg from it.
pub fn checks(h: &mut Html, machine: &Machine, _ctx: &Context) -> Result<()> {
    h.h2_id("checks", "Kinematic checks");
    h.p(&format!(
        "Each pose: inverse kinematics, every limit, forward kinematics started from the \
         home pose (held coordinates taken from the pose) compared with the pose (pass: \
         ≤ {ROUND_TRIP_TOL_MM:.0e} mm and ≤ {ROUND_TRIP_TOL_RAD:.0e} rad), the analytic \
         Jacobian against central finite differences (pass: relative ≤ {JACOBIAN_TOL:.0e}) \
         and the condition number of the Jacobian's driven columns."
    ));
    let table = machine_check_table(machine, 20.0, 5f64.to_radians());
    h.raw(&check_table_html(machine, &table));

    Ok(())
}

fn check_table_html(machine: &Machine, rows: &[CheckRow]) -> String {
    let m = machine.mechanism();
    let mut head: Vec<String> = vec!["pose".into()];
    // A machine tool's joints share their names with its coordinates (X, Y, Z, B, C):
    // the columns say they are the joints.
    let shared = m
        .actuators()
        .iter()
        .any(|a| m.coordinates().iter().any(|c| c.name == a.name));
    let prefix = if shared { "joint " } else { "" };
    head.extend(
        m.actuators()
            .iter()
            .map(|a| format!("{prefix}{} [{}]", a.name, a.quantity.unit())),
    );
    head.extend(
        [
            "FK round trip [mm / rad]",
            "Jacobian vs FD",
            "condition",
            "limits",
        ]
        .map(String::from),
    );
    let body: Vec<Vec<String>> = rows.iter().map(|r| check_row_html(m, r)).collect();
    let head_refs: Vec<&str> = head.iter().map(String::as_str).collect();
    Html::table_string(&head_refs, &body)
}

/// The cells of one checked pose: actuators, round trip, Jacobian, condition, limits.
fn check_row_html(m: &dyn pkm::DynMechanism, r: &CheckRow) -> Vec<String> {
    let mut cells = vec![esc(&r.label)];
    match &r.actuators {
        Some(q) => cells.extend(q.iter().map(|v| format!("{:.4}", Shown(*v)))),
        None => cells.extend(m.actuators().iter().map(|_| "-".to_string())),
    }
    cells.push(match &r.round_trip {
        Some(t) => {
            let ok =
                t.position_error <= ROUND_TRIP_TOL_MM && t.orientation_error <= ROUND_TRIP_TOL_RAD;
            format!(
                "{} {:.1e} / {:.1e}",
                mark(ok),
                t.position_error,
                t.orientation_error
            )
        }
        None => "-".into(),
    });
    cells.push(match r.jacobian_error {
        Some(e) => format!("{} {:.1e}", mark(e <= JACOBIAN_TOL), e),
        None => "-".into(),
    });
    cells.push(r.condition.map(|c| format!("{c:.3}")).unwrap_or("-".into()));
    let mut lim = if r.violations.is_empty() {
        "<span class=\"ok\">all satisfied</span>".to_string()
    } else {
        r.violations
            .iter()
            .map(|v| format!("<span class=\"bad\">{}</span>", esc(&v.to_string())))
            .collect::<Vec<_>>()
            .join("<br>")
    };
    if let Some(e) = &r.error {
        lim.push_str(&format!("<br><span class=\"bad\">{}</span>", esc(e)));
    }
    cells.push(lim);
    cells
}
