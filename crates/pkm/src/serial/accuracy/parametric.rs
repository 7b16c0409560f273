//! Serial chains (seed 003) in the accuracy engine: the primary deviations of every
//! link and joint and the installation angles, the deviated pose from the product of
//! the deviated transforms (eqs. 1-4), analytic sensitivities.
//!
//! Angular deviations are completed where the paper completes them (eq. 3): the
//! angular deviations given for a link (measured or toleranced, at most three) are
//! those of a triple that determines the link's rotation, and the other six follow from
//! orthonormality, per evaluation (so per Monte Carlo sample): the link turns rigidly.
//! Deviations that mean nothing alone are refused with the reason: an angle between two
//! nominally aligned axes (`cos(0 + alpha)`: no first-order effect, no sign), more than
//! three angles of one link, triples that leave a rotation open (a whole row or column),
//! and the installation angles of a machine with a workpiece chain (they turn tool and
//! part alike).

use nalgebra::{Matrix4, SVector, Vector3};

use crate::accuracy::{Evaluate, Parameter, ParameterKind, Parametric, PoseError};
use crate::error::{Error, Result};
use crate::mechanism::Mechanism;
use crate::serial::completion::TripleCompletion;
use crate::serial::deviations::{apply, clear, error_between, zero_deviations};
use crate::serial::machine::{ChainDeviations, Parameter as Deviation, SerialMachine};
use crate::units::Quantity;

/// The engine's parameter list of a serial machine, in the order of
/// [`SerialMachine::all_parameters`].
pub fn serial_parameters(m: &SerialMachine) -> Vec<Parameter> {
    m.all_parameters()
        .iter()
        .map(|p| {
            let kind = match p {
                Deviation::Delta { .. } => ParameterKind::LinkOffset,
                Deviation::Alpha { .. } => ParameterKind::AngularDeviation,
                Deviation::Dq { .. } => ParameterKind::DrivePositioning,
                Deviation::Installation { .. } => ParameterKind::Installation,
            };
            let quantity = if m.is_angular(p) {
                Quantity::Angle
            } else {
                Quantity::Length
            };
            Parameter::new(m.parameter_name(p), quantity, kind)
        })
        .collect()
}

/// A link whose angular deviations are completed from a triple (eq. 3).
#[derive(Debug, Clone, PartialEq)]
pub struct LinkCompletion {
    /// 0 = tool chain, 1 = workpiece chain.
    pub chain: usize,
    /// Link index in the chain.
    pub link: usize,
    /// The triple and its solver.
    pub triple: TripleCompletion,
}

/// Every triple of the nine positions, in order.
fn triples() -> impl Iterator<Item = [(usize, usize); 3]> {
    let pos: Vec<(usize, usize)> = (0..9).map(|e| (e / 3, e % 3)).collect();
    (0..9).flat_map(move |a| {
        let pos = pos.clone();
        (a + 1..9).flat_map(move |b| {
            let pos = pos.clone();
            (b + 1..9).map(move |c| [pos[a], pos[b], pos[c]])
        })
    })
}

/// The first triple containing `given` positions that determines a link's rotation, or
/// the reason none does.
fn triple_for(
    nominal: &nalgebra::Matrix3<f64>,
    given: &[(usize, usize)],
) -> std::result::Result<TripleCompletion, String> {
    let mut reason = None;
    for t in triples().filter(|t| given.iter().all(|g| t.contains(g))) {
        match TripleCompletion::new(nominal, t) {
            Ok(c) => return Ok(c),
            Err(r) => {
                reason.get_or_insert(r);
            }
        }
    }
    Err(reason.unwrap_or_else(|| "no triple of positions contains them".into()))
}

/// The completions for deviations given on the parameters `given` (indices of
/// [`SerialMachine::all_parameters`]), or the reason a given parameter cannot be given.
pub fn serial_completions(m: &SerialMachine, given: &[usize]) -> Result<Vec<LinkCompletion>> {
    let mut out = Vec::new();
    for ((chain, link), pos) in given_angles(m, given)? {
        let names = || {
            pos.iter()
                .map(|&(row, col)| {
                    m.parameter_name(&Deviation::Alpha {
                        chain,
                        link,
                        row,
                        col,
                    })
                })
                .collect::<Vec<_>>()
        };
        if pos.len() > 3 {
            return Err(refuse(
                names(),
                "at most three angular deviations of a link are independent (eq. 3: the \
                 other six follow from the orthonormality of its block)"
                    .into(),
            ));
        }
        let ch = if chain == 0 {
            &m.tool
        } else {
            m.workpiece
                .as_ref()
                .expect("a workpiece parameter has its chain")
        };
        let nominal = ch.links[link].rotation;
        let triple = triple_for(&nominal, &pos).map_err(|r| refuse(names(), r))?;
        out.push(LinkCompletion {
            chain,
            link,
            triple,
        });
    }
    Ok(out)
}

/// The refusal of deviations on the parameters `names`, for `reason`.
fn refuse(names: Vec<String>, reason: String) -> Error {
    Error::InvalidInput {
        what: "deviation".into(),
        message: format!("{} cannot be given: {reason}", names.join(", ")),
    }
}

/// Positions of angular deviations by link `(chain, link)`.
type AnglesByLink = std::collections::BTreeMap<(usize, usize), Vec<(usize, usize)>>;

/// The angular deviations among the parameters `given`, their positions by link
/// `(chain, link)`; refuses an index beyond the parameters and installation angles
/// that cannot be given.
fn given_angles(m: &SerialMachine, given: &[usize]) -> Result<AnglesByLink> {
    let params = m.all_parameters();
    let mut per_link = AnglesByLink::default();
    for &k in given {
        match params.get(k) {
            None => {
                return Err(Error::InvalidInput {
                    what: "deviation".into(),
                    message: format!("parameter index {k} beyond the machine's {}", params.len()),
                })
            }
            Some(p @ Deviation::Installation { .. }) if m.workpiece.is_some() => {
                return Err(refuse(
                    vec![m.parameter_name(p)],
                    "the installation angles turn the bed, and with it tool and part alike: \
                     they cannot change the tool relative to a part on the workpiece chain"
                        .into(),
                ))
            }
            Some(Deviation::Alpha {
                chain,
                link,
                row,
                col,
            }) => {
                let v = per_link.entry((*chain, *link)).or_default();
                if !v.contains(&(*row, *col)) {
                    v.push((*row, *col));
                }
            }
            Some(_) => {}
        }
    }
    Ok(per_link)
}

/// Which parameters can be toleranced one by one: per link the angular deviations of
/// the first triple that determines its rotation (the others follow from it), every
/// other parameter but the installation angles of a machine with a workpiece chain.
pub fn serial_tolerable(m: &SerialMachine) -> Vec<bool> {
    let params = m.all_parameters();
    let mut chosen: std::collections::BTreeMap<(usize, usize), Vec<(usize, usize)>> =
        Default::default();
    params
        .iter()
        .map(|p| match *p {
            Deviation::Installation { .. } => m.workpiece.is_none(),
            Deviation::Alpha {
                chain,
                link,
                row,
                col,
            } => {
                let triple = chosen.entry((chain, link)).or_insert_with(|| {
                    let ch = if chain == 0 {
                        &m.tool
                    } else {
                        m.workpiece.as_ref().expect("chain")
                    };
                    triple_for(&ch.links[link].rotation, &[])
                        .map(|t| t.positions().to_vec())
                        .unwrap_or_default()
                });
                triple.contains(&(row, col))
            }
            _ => true,
        })
        .collect()
}

/// The exact tool pose of the deviated chains against the nominal one at fixed joints.
#[derive(Clone)]
pub struct SerialEvaluator<'a> {
    m: &'a SerialMachine,
    completions: &'a [LinkCompletion],
    params: Vec<Deviation>,
    qt: Vec<f64>,
    qw: Vec<f64>,
    dev: Vec<ChainDeviations>,
    /// Parameters the last evaluation set (to be cleared by the next).
    dirty: Vec<usize>,
    nominal: Matrix4<f64>,
}

impl<'a> SerialEvaluator<'a> {
    fn new(m: &'a SerialMachine, completions: &'a [LinkCompletion], q: &[f64]) -> Result<Self> {
        let (qt, qw) = q.split_at(m.tool.dof().min(q.len()));
        Ok(SerialEvaluator {
            m,
            completions,
            params: m.all_parameters(),
            qt: qt.to_vec(),
            qw: qw.to_vec(),
            dev: zero_deviations(m),
            dirty: Vec::new(),
            nominal: m.pose(qt, qw, &[])?,
        })
    }

    /// Analytic sensitivities; those of completed triples by central differences of
    /// the completed evaluation (the link turns rigidly, its other angles follow).
    fn analytic(&self) -> Result<Vec<PoseError>> {
        let mut s: Vec<PoseError> = self
            .m
            .sensitivities(&self.qt, &self.qw, &[], &self.params)?
            .into_iter()
            .map(|(position, orientation)| PoseError {
                position,
                orientation,
            })
            .collect();
        let mut ev = self.clone();
        for c in self.completions {
            for (row, col) in c.triple.positions() {
                let p = Deviation::Alpha {
                    chain: c.chain,
                    link: c.link,
                    row,
                    col,
                };
                let Some(k) = self.params.iter().position(|x| *x == p) else {
                    continue;
                };
                let h = 1e-6;
                let plus = ev.pose_error(&[(k, h)])?;
                let minus = ev.pose_error(&[(k, -h)])?;
                s[k] = PoseError {
                    position: (plus.position - minus.position) / (2.0 * h),
                    orientation: (plus.orientation - minus.orientation) / (2.0 * h),
                };
            }
        }
        Ok(s)
    }
}

impl Evaluate for SerialEvaluator<'_> {
    fn pose_error(&mut self, deviations: &[(usize, f64)]) -> Result<PoseError> {
        // Only the slots the last call set go back to zero (a Monte Carlo sample sets
        // the same few of the machine's ~90 each time).
        for &k in &self.dirty {
            clear(&mut self.dev, &self.params[k]);
        }
        self.dirty.clear();
        for &(k, v) in deviations {
            let p = self.params.get(k).ok_or_else(|| Error::InvalidInput {
                what: "deviation".into(),
                message: format!(
                    "parameter index {k} beyond the machine's {}",
                    self.params.len()
                ),
            })?;
            apply(&mut self.dev, p, v);
            self.dirty.push(k);
        }
        for c in self.completions {
            let l = &mut self.dev[c.chain].links[c.link];
            let measured = c.triple.positions().map(|(r, k)| l.alpha[(r, k)]);
            l.block = if measured == [0.0; 3] {
                None
            } else {
                Some(c.triple.complete_block(measured)?)
            };
        }
        let b = self.m.pose(&self.qt, &self.qw, &self.dev)?;
        let (position, orientation) = error_between(&self.nominal, &b);
        Ok(PoseError {
            position,
            orientation,
        })
    }
}

/// A serial machine's prepared sensitivity plan for one list of parameters.
#[derive(Debug, Clone)]
pub(crate) struct SerialScratch {
    which: Vec<usize>,
    plan: super::sensitivity::SensitivityPlan,
    frames: super::sensitivity::SensitivityScratch,
    buf: Vec<(Vector3<f64>, Vector3<f64>)>,
}

/// [`Parametric::sensitivities_into`] of a serial machine at joints `q` (tool chain,
/// then workpiece chain): the plan for `which` built on the first call (or when
/// `which` changes), then evaluated without allocating.
fn serial_sensitivities_into(
    m: &SerialMachine,
    completions: &[LinkCompletion],
    q: &[f64],
    which: &[usize],
    s: &mut crate::accuracy::SensitivityScratch,
    out: &mut [PoseError],
) -> Result<Vector3<f64>> {
    if s.serial.as_ref().is_none_or(|x| x.which != which) {
        let all = m.all_parameters();
        let params = which
            .iter()
            .map(|&k| {
                all.get(k).copied().ok_or_else(|| Error::InvalidInput {
                    what: "sensitivities".into(),
                    message: format!("parameter index {k} beyond the machine's {}", all.len()),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let plan = super::sensitivity::SensitivityPlan::new(m, completions, &params)?;
        s.serial = Some(SerialScratch {
            which: which.to_vec(),
            frames: plan.scratch(),
            plan,
            buf: vec![(Vector3::zeros(), Vector3::zeros()); which.len()],
        });
    }
    let sc = s.serial.as_mut().expect("set above");
    if out.len() != which.len() {
        return Err(Error::InvalidInput {
            what: "sensitivities".into(),
            message: format!("expected {} outputs, got {}", which.len(), out.len()),
        });
    }
    let (qt, qw) = q.split_at(m.tool.dof().min(q.len()));
    let axis = sc.plan.evaluate(qt, qw, &mut sc.frames, &mut sc.buf)?;
    for (o, (position, orientation)) in out.iter_mut().zip(&sc.buf) {
        *o = PoseError {
            position: *position,
            orientation: *orientation,
        };
    }
    Ok(axis)
}

/// `mech` with the completions for `given`, `None` when they are its own already.
fn with_completions<T: Clone>(
    mech: &T,
    machine: &SerialMachine,
    current: &[LinkCompletion],
    given: &[usize],
    field: fn(&mut T) -> &mut Vec<LinkCompletion>,
) -> Result<Option<T>> {
    let completions = serial_completions(machine, given)?;
    if completions == current {
        return Ok(None);
    }
    let mut m = mech.clone();
    *field(&mut m) = completions;
    Ok(Some(m))
}

/// The methods every serial mechanism shares (they differ in the joints commanded for
/// a pose: the pose itself in joint space, the inverse solution for a robot or TCP
/// coordinates).
macro_rules! serial_parametric_common {
    (@ $x:ty) => {
        fn parameters(&self) -> Vec<Parameter> {
            serial_parameters(&self.machine())
        }
        /// At the joints `q` the caller solved (actuators are the joints).
        fn sensitivities_into(
            &self,
            _x: &$x,
            q: &$x,
            which: &[usize],
            s: &mut crate::accuracy::SensitivityScratch,
            out: &mut [PoseError],
        ) -> Result<Vector3<f64>> {
            serial_sensitivities_into(
                &self.machine(),
                &self.completions,
                q.as_slice(),
                which,
                s,
                out,
            )
        }
        fn analytic_sensitivities(&self, x: &$x) -> Option<Result<Vec<PoseError>>> {
            Some(self.evaluator(x).and_then(|e| e.analytic()))
        }
        fn with_given(&self, given: &[usize]) -> Result<Option<Self>> {
            with_completions(self, &self.machine(), &self.completions, given, |m| {
                &mut m.completions
            })
        }
        fn tolerable(&self) -> Vec<bool> {
            serial_tolerable(&self.machine())
        }
    };
}

impl<const N: usize> Parametric<N, N> for crate::serial::mechanism::SerialMechanism<N> {
    type Evaluator<'a> = SerialEvaluator<'a>;
    serial_parametric_common!(@ SVector<f64, N>);
    fn evaluator(&self, x: &SVector<f64, N>) -> Result<SerialEvaluator<'_>> {
        SerialEvaluator::new(self.machine(), &self.completions, x.as_slice())
    }
}

/// `Parametric` of a serial mechanism whose pose coordinates are not its joints: the
/// joints commanded for pose `x` are the nominal inverse solution (a robot's tool pose,
/// a machine tool's TCP coordinates: the error is the tool's relative to the part with
/// the machine's deviations at them).
macro_rules! serial_parametric_by_inverse {
    ($x:ty) => {
        type Evaluator<'a> = SerialEvaluator<'a>;
        serial_parametric_common!(@ $x);
        fn evaluator(&self, x: &$x) -> Result<SerialEvaluator<'_>> {
            let q = self.inverse(x)?;
            SerialEvaluator::new(&self.machine(), &self.completions, q.as_slice())
        }
    };
}

impl Parametric<6, 6> for crate::serial::arm::SerialArm {
    serial_parametric_by_inverse!(SVector<f64, 6>);
}

impl<const N: usize> Parametric<N, N> for crate::serial::tcp::TcpMachine<N> {
    serial_parametric_by_inverse!(SVector<f64, N>);
}
