//! The sensitivities of a serial machine's tool pose to a fixed list of primary
//! deviations at many joint configurations (a program's samples): prepared once,
//! evaluated per pose from one walk of each chain, without allocating.
//!
//! The formula is [`SerialMachine::sensitivities`]' (`dT/dp = T_before dM/dp T_after`)
//! rewritten with frames instead of 4 x 4 products. With `(R_k, o_k)` the world frame
//! before factor `k` of a chain, `(R_k+1, o_k+1)` after it, `p` the tool tip (world)
//! and `T_w` the workpiece chain's end, a deviation entering factor `k` with local
//! derivative `dM = [D d; 0 0]` moves the tip relative to the part by
//! `dp = +- R_w^T R_k (D b + d)`, `b = R_k+1^T (p - o_k+1)` the tip in the frame after
//! the factor, and turns the tool relative to the part by `w = +- R_w^T R_k
//! vee(skew(D M^T))` (`M` the factor's nominal rotation; `+` tool chain, `-`
//! workpiece chain, whose deviation moves the part under the tool: `d(T_w^-1 T_t) =
//! -T_w^-1 dT_w T_w^-1 T_t`). A joint's own positioning deviation is the classic
//! Jacobian column: `(z x (p - o), z)` for a turn about `z`, `(z, 0)` for a slide. The
//! angles of a completed link (eq. 3) enter through the completed block's derivative
//! (central differences of the completion, `h = 1e-6` rad, once per plan).
//!
//! Exact at the nominal geometry (deviations zero), where the accuracy engine takes
//! its sensitivities; tested against [`SerialMachine::sensitivities`].

use nalgebra::{Matrix3, Vector3};

use crate::accuracy::LinkCompletion;
use crate::error::{Error, Result};
use crate::serial::machine::{installation_axis, Parameter, SerialMachine};
use crate::serial::{affine_mul, apply_joint, link_affine, Affine, JointKind, LinkDeviation};
use crate::serial::{Chain, AFFINE_IDENTITY};

/// One factor of a chain: a link's fixed transform or a joint.
#[derive(Debug, Clone, PartialEq)]
enum Factor {
    Link(Affine),
    Joint(JointKind),
}

/// How one deviation moves the tool.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Item {
    /// A link factor's constant derivative: rotation part `d`, translation part `t`,
    /// and the local small rotation `w = vee(skew(D M^T))`.
    Link {
        chain: usize,
        factor: usize,
        d: Matrix3<f64>,
        t: Vector3<f64>,
        w: Vector3<f64>,
    },
    /// A joint's positioning deviation.
    Joint {
        chain: usize,
        factor: usize,
        kind: JointKind,
    },
    /// An installation angle about world axis `axis` (no workpiece chain).
    Installation { axis: Vector3<f64> },
    /// No first-order effect (an installation angle under a workpiece chain: the part
    /// turns with the machine).
    Zero,
}

/// Sensitivities of one machine's tool pose to a list of deviations, prepared.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityPlan {
    chains: Vec<Vec<Factor>>,
    dofs: Vec<usize>,
    items: Vec<Item>,
}

/// Per-thread scratch of a [`SensitivityPlan`]: the frames of each chain.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityScratch {
    frames: Vec<Vec<Affine>>,
}

fn factors_of(ch: &Chain) -> Vec<Factor> {
    let zero = LinkDeviation::default();
    let mut f = Vec::with_capacity(2 * ch.links.len());
    for link in &ch.links {
        if let Some(j) = &link.joint {
            f.push(Factor::Joint(j.kind));
        }
        f.push(Factor::Link(link_affine(link, &zero)));
    }
    f
}

fn rotation(a: &Affine) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| a[r][c])
}

fn origin(a: &Affine) -> Vector3<f64> {
    Vector3::new(a[0][3], a[1][3], a[2][3])
}

/// The plan's item for parameter `p` of machine `m` (its `chains`, at joints `qt`,
/// `qw` zero).
fn plan_item(
    m: &SerialMachine,
    completions: &[LinkCompletion],
    chains: &[&Chain],
    qt: &[f64],
    qw: &[f64],
    p: &Parameter,
) -> Result<Item> {
    Ok(match *p {
        Parameter::Installation { axis } => {
            if m.workpiece.is_some() {
                Item::Zero
            } else {
                Item::Installation {
                    axis: installation_axis(&Vector3::zeros(), axis.min(2)),
                }
            }
        }
        Parameter::Dq { chain, joint } => {
            let (c, factor, _) = super::derivative(m, p, qt, qw, &[])?;
            let kind = chains[c]
                .joints()
                .nth(joint)
                .map(|j| j.kind)
                .ok_or_else(|| Error::InvalidInput {
                    what: "deviation".into(),
                    message: format!("chain {chain} has no joint {joint}"),
                })?;
            Item::Joint {
                chain: c,
                factor,
                kind,
            }
        }
        Parameter::Delta { chain, link, .. } | Parameter::Alpha { chain, link, .. } => {
            let (c, factor, dm) = super::derivative(m, p, qt, qw, &[])?;
            let mut d: Matrix3<f64> = dm.fixed_view::<3, 3>(0, 0).into_owned();
            let t: Vector3<f64> = dm.fixed_view::<3, 1>(0, 3).into_owned();
            if let Parameter::Alpha { row, col, .. } = *p {
                if let Some(dc) = completed_derivative(completions, chain, link, (row, col))? {
                    d = dc;
                }
            }
            let nominal = chains[c].links[link].rotation;
            let w = crate::rotation::skew_vee(&(d * nominal.transpose()));
            Item::Link {
                chain: c,
                factor,
                d,
                t,
                w,
            }
        }
    })
}

/// The derivative of the block of link `link` of chain `chain` by its angular
/// deviation at `position` when a triple completes that link and holds the position
/// (central differences of the completion), else `None`.
fn completed_derivative(
    completions: &[LinkCompletion],
    chain: usize,
    link: usize,
    position: (usize, usize),
) -> Result<Option<Matrix3<f64>>> {
    let completed = completions
        .iter()
        .find(|x| x.chain == chain && x.link == link && x.triple.positions().contains(&position));
    let Some(cpl) = completed else {
        return Ok(None);
    };
    let i = cpl
        .triple
        .positions()
        .iter()
        .position(|&x| x == position)
        .expect("contained");
    let h = 1e-6;
    let mut plus = [0.0; 3];
    plus[i] = h;
    let mut minus = [0.0; 3];
    minus[i] = -h;
    Ok(Some(
        (cpl.triple.complete_block(plus)? - cpl.triple.complete_block(minus)?) / (2.0 * h),
    ))
}

impl SensitivityPlan {
    /// The plan for `params` of machine `m` whose links `completions` complete their
    /// angular deviations (eq. 3).
    pub fn new(
        m: &SerialMachine,
        completions: &[LinkCompletion],
        params: &[Parameter],
    ) -> Result<Self> {
        let chains: Vec<&Chain> = std::iter::once(&m.tool).chain(m.workpiece.iter()).collect();
        let zeros: Vec<Vec<f64>> = chains.iter().map(|c| vec![0.0; c.dof()]).collect();
        let qw: &[f64] = zeros.get(1).map(|v| v.as_slice()).unwrap_or(&[]);
        let items = params
            .iter()
            .map(|p| plan_item(m, completions, &chains, &zeros[0], qw, p))
            .collect::<Result<Vec<_>>>()?;
        Ok(SensitivityPlan {
            chains: chains.iter().map(|c| factors_of(c)).collect(),
            dofs: chains.iter().map(|c| c.dof()).collect(),
            items,
        })
    }

    /// Scratch for [`SensitivityPlan::evaluate`].
    pub fn scratch(&self) -> SensitivityScratch {
        SensitivityScratch {
            frames: self
                .chains
                .iter()
                .map(|c| vec![AFFINE_IDENTITY; c.len() + 1])
                .collect(),
        }
    }

    /// The sensitivities (tool-point displacement, mm per unit; small rotation of the
    /// tool frame, rad per unit; both in the workpiece frame) of the plan's deviations
    /// at joints `qt` (tool chain) and `qw` (workpiece chain) into `out` (one per
    /// deviation of the plan). Returns the tool axis (the tool frame's Z) in the
    /// workpiece frame.
    pub fn evaluate(
        &self,
        qt: &[f64],
        qw: &[f64],
        s: &mut SensitivityScratch,
        out: &mut [(Vector3<f64>, Vector3<f64>)],
    ) -> Result<Vector3<f64>> {
        self.check_sizes(qt, qw, s, out)?;
        self.walk(qt, qw, s);
        let tool = s.frames[0].last().expect("frames");
        let p = origin(tool);
        // World to part: the workpiece chain's end, else the world itself.
        let (rw_t, ow) = match s.frames.get(1) {
            Some(w) => {
                let end = w.last().expect("frames");
                (rotation(end).transpose(), origin(end))
            }
            None => (Matrix3::identity(), Vector3::zeros()),
        };
        for (o, item) in out.iter_mut().zip(&self.items) {
            *o = item_sensitivity(item, &s.frames, &p, &rw_t, &ow);
        }
        Ok(rw_t * Vector3::new(tool[0][2], tool[1][2], tool[2][2]))
    }

    /// Checks the sizes of [`SensitivityPlan::evaluate`]'s arguments against the plan.
    fn check_sizes(
        &self,
        qt: &[f64],
        qw: &[f64],
        s: &SensitivityScratch,
        out: &[(Vector3<f64>, Vector3<f64>)],
    ) -> Result<()> {
        if out.len() != self.items.len()
            || qt.len() != self.dofs[0]
            || qw.len() != self.dofs.get(1).copied().unwrap_or(0)
            || s.frames.len() != self.chains.len()
        {
            return Err(Error::InvalidInput {
                what: "sensitivities".into(),
                message: format!(
                    "expected {} outputs and {:?} joint values, got {} and {}, {}",
                    self.items.len(),
                    self.dofs,
                    out.len(),
                    qt.len(),
                    qw.len()
                ),
            });
        }
        Ok(())
    }

    /// The frames after every factor of each chain at joints `qt`, `qw` into `s`.
    #[inline]
    fn walk(&self, qt: &[f64], qw: &[f64], s: &mut SensitivityScratch) {
        for (c, q) in [qt, qw].iter().enumerate().take(self.chains.len()) {
            let frames = &mut s.frames[c];
            let mut t = AFFINE_IDENTITY;
            let mut k = 0;
            frames[0] = t;
            for (i, f) in self.chains[c].iter().enumerate() {
                match f {
                    Factor::Joint(kind) => {
                        let v = q[k];
                        let sc = match kind {
                            JointKind::Revolute => v.sin_cos(),
                            JointKind::Prismatic => (0.0, 1.0),
                        };
                        apply_joint(&mut t, *kind, v, sc);
                        k += 1;
                    }
                    Factor::Link(l) => t = affine_mul(&t, l),
                }
                frames[i + 1] = t;
            }
        }
    }
}

/// The sensitivity of one deviation `item` from the chains' `frames`, with the tool
/// point `p`, the world-to-part rotation `rw_t` and the part origin `ow`.
#[inline(always)]
fn item_sensitivity(
    item: &Item,
    frames: &[Vec<Affine>],
    p: &Vector3<f64>,
    rw_t: &Matrix3<f64>,
    ow: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let sign = |c: usize| if c == 0 { 1.0 } else { -1.0 };
    match *item {
        Item::Link {
            chain,
            factor,
            ref d,
            ref t,
            ref w,
        } => {
            let before = &frames[chain][factor];
            let after = &frames[chain][factor + 1];
            let b = rotation(after).transpose() * (p - origin(after));
            let rk = rw_t * rotation(before) * sign(chain);
            (rk * (d * b + t), rk * w)
        }
        Item::Joint {
            chain,
            factor,
            kind,
        } => {
            let f = &frames[chain][factor];
            let z = Vector3::new(f[0][2], f[1][2], f[2][2]);
            let (v, w) = match kind {
                JointKind::Revolute => (z.cross(&(p - origin(f))), z),
                JointKind::Prismatic => (z, Vector3::zeros()),
            };
            (rw_t * v * sign(chain), rw_t * w * sign(chain))
        }
        Item::Installation { axis } => (axis.cross(&(p - ow)), axis),
        Item::Zero => (Vector3::zeros(), Vector3::zeros()),
    }
}
