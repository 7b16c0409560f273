//! The report's references: values published elsewhere for poses of this machine
//! (`[[reference]]` entries) beside pkm's.

use anyhow::Result;
use pkm::verify::{check_references, ReferenceCheck};
use pkm::Machine;

use super::html::{esc, Html};
use super::{drawing, mark, Context};
use crate::poses::Shown;

/// Every `[[reference]]` of the machine file, checked.
pub fn section(h: &mut Html, machine: &Machine, _ctx: &Context) -> Result<()> {
    let references = check_references(machine);
    h.h2_id("references", "Reproduced references");
    h.p(
        "Values published elsewhere (a paper's table, a CAD model) for poses of this \
         machine, from the <code>[[reference]]</code> entries of its file, beside \
         pkm's values.",
    );
    for r in &references {
        one(h, machine, r)?;
    }
    Ok(())
}

fn one(h: &mut Html, machine: &Machine, r: &ReferenceCheck) -> Result<()> {
    let m = machine.mechanism();
    let mark_of = if r.discrepancy {
        "<span class=\"bad\">discrepancy with the source</span>"
    } else {
        mark(r.pass)
    };
    h.raw(&format!("<h3>{} {}</h3>", mark_of, esc(&r.source)));
    h.p(&format!(
        "Pose <code>{}</code> (mm, deg), tolerance {} per component.",
        r.pose
            .iter()
            .map(|v| format!("{v}"))
            .collect::<Vec<_>>()
            .join(", "),
        r.tolerance
    ));
    if let Some(n) = &r.note {
        h.p(&format!("<em>Note:</em> {}", esc(n)));
    }
    if let Some(e) = &r.error {
        h.p(&format!("<span class=\"bad\">{}</span>", esc(e)));
    }
    h.table(
        &["value", "published", "pkm", "deviation", "within tolerance"],
        &item_rows(r),
    );
    if r.error.is_none() {
        let x = pkm::dynamic::pose_from_user(m, &r.pose, pkm::Convention::Rpy)?;
        let sk = m.skeleton(&x)?;
        let home = m.skeleton(&m.home())?;
        let mut svgs = String::new();
        for v in drawing::views_for(&sk) {
            svgs.push_str(&drawing::view_svg(&[&sk, &home], v, (400, 400))?);
        }
        h.p("The machine at this pose (home pose faint):");
        h.raw(&format!("<div class=\"views\">{svgs}</div>"));
    }
    Ok(())
}

/// One row per value of the reference: published, pkm's, deviation, pass.
fn item_rows(r: &ReferenceCheck) -> Vec<Vec<String>> {
    let fmt = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{:.3}", Shown(*x)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    r.items
        .iter()
        .map(|i| {
            vec![
                format!("{} {}", i.what, esc(&i.name)),
                match &i.published {
                    Some(p) => format!("{} (pkm's correction: {})", fmt(p), fmt(&i.expected)),
                    None => fmt(&i.expected),
                },
                i.computed.as_deref().map(fmt).unwrap_or("-".into()),
                i.deviation
                    .map(|d| format!("{d:.4} {}", i.unit))
                    .unwrap_or("-".into()),
                mark(i.pass).into(),
            ]
        })
        .collect()
}
