//! `Machine.motion`: a G-code program or a path run through the mechanism, the
//! samples returned as numpy columns and the summary as a dict (mm, rad, s). It calls
//! `pkm::analysis::motion` with the GIL released.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::analyses::positive;
use crate::convert::{self, rows, vec1, vec2};
use crate::errors::{invalid, to_py};
use crate::machine::Machine;

/// Collects a run's samples in columns (mm, rad, s); with `keep` false, nothing
/// (the summary only). The number of samples is bounded by the library's work limit
/// ([`pkm::motion::program::FeedOptions::max_samples`]), checked before a move is
/// sampled.
#[derive(Default)]
struct Columns {
    keep: bool,
    t: Vec<f64>,
    line: Vec<i64>,
    x: Vec<f64>,
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
}

impl pkm::analysis::motion::SampleSink for Columns {
    fn sample(&mut self, s: &pkm::analysis::motion::SampleRow) -> pkm::Result<()> {
        if self.keep {
            self.t.push(s.t);
            self.line.push(s.line.map_or(-1, |l| l as i64));
            self.x.extend_from_slice(s.x);
            self.q.extend_from_slice(s.q);
            self.qd.extend_from_slice(s.qd);
            self.qdd.extend_from_slice(s.qdd);
        }
        Ok(())
    }
}

fn profile_kind(s: &str) -> PyResult<pkm::motion::program::ProfileKind> {
    use pkm::motion::program::ProfileKind;
    match s {
        "constant" => Ok(ProfileKind::Constant),
        "trapezoid" => Ok(ProfileKind::Trapezoid),
        "scurve" => Ok(ProfileKind::Scurve),
        p => Err(invalid(
            "profile",
            format!("expected `constant`, `trapezoid` or `scurve`, got `{p}`"),
        )),
    }
}

#[pymethods]
impl Machine {
    /// Runs a G-code program or a path through the mechanism (pkm motion): actuator
    /// position, velocity and acceleration over time, limits along the way, and the
    /// same path on a serial machine.
    ///
    /// Give `gcode` (the program's text, or a `pathlib.Path` to it) or `path` (an
    /// (N, P) array of waypoints in the machine's coordinates, mm and rad, run as
    /// straight moves at `feed`). `feed` replaces the program's F words: mm/s along
    /// the path (as `pkm motion` measures it: deg/s for a move of angles alone);
    /// `profile`: `constant`, `trapezoid` or `scurve` with `acceleration` (mm/s^2)
    /// and `jerk` (mm/s^3); `rapid` (mm/s) for G0; `start`: the pose the program
    /// starts from (default home); `tool_length` (mm) for G43 without a table.
    /// Sampling: `rate` (Hz, default 1000) or `points` per move. A run beyond
    /// `max_samples` samples is refused before the move that would cross it is
    /// sampled. `samples=False` keeps no sample (the summary only: a long program
    /// in constant memory).
    ///
    /// Returns a dict: `t` (N,), `line` (N,) (-1: no line), `x` (N, P), `q`, `qd`,
    /// `qdd` (N, A) arrays (mm, rad, s; empty with `samples=False`), `columns` (their
    /// names), `summary` (as `pkm motion` writes it: per actuator and serial axis
    /// statistics in mm and deg, ratios, violations, feed override, singular
    /// passages) and `notes`. A robot's joints continue from sample to sample (its
    /// posture and the whole turns of its wrist), as a controller moves it.
    #[pyo3(signature = (gcode = None, path = None, *, feed = None, profile = "constant",
        acceleration = None, jerk = None, rapid = None, rate = None, points = None,
        start = None, tool_length = None, max_samples = 2_000_000, samples = true))]
    #[allow(clippy::too_many_arguments)]
    fn motion<'py>(
        &self,
        py: Python<'py>,
        gcode: Option<&Bound<'py, PyAny>>,
        path: Option<&Bound<'py, PyAny>>,
        feed: Option<f64>,
        profile: &str,
        acceleration: Option<f64>,
        jerk: Option<f64>,
        rapid: Option<f64>,
        rate: Option<f64>,
        points: Option<usize>,
        start: Option<&Bound<'py, PyAny>>,
        tool_length: Option<f64>,
        max_samples: usize,
        samples: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let m = self.m();
        let p = m.coordinates().len();
        let mut opts = pkm::analysis::motion::feed_options(&self.inner);
        opts.profile = profile_kind(profile)?;
        if let Some(x) = positive("acceleration", acceleration)? {
            opts.acceleration = x;
        }
        if let Some(x) = positive("jerk", jerk)? {
            opts.jerk = x;
        }
        if let Some(x) = positive("rapid", rapid)? {
            opts.rapid = x;
        }
        opts.feed = positive("feed", feed)?;
        opts.max_samples = max_samples as u64;
        let sampling = sampling(rate, points)?;
        let from = convert::one_pose(start, p, "start")?;
        let src = Src::of(gcode, path, p)?;
        let mut cols = Columns {
            keep: samples,
            ..Default::default()
        };
        let inner = self.inner.clone();
        let run = py
            .detach(|| {
                let source = src.into_source(from, tool_length);
                pkm::analysis::motion::run_motion(&inner, source, &opts, sampling, &mut cols)
            })
            .map_err(to_py)?;
        run_dict(py, m, cols, run)
    }
}

/// A run as `Machine.motion` returns it: the sample columns, their names, the
/// summary and the notes.
fn run_dict<'py>(
    py: Python<'py>,
    m: &dyn pkm::DynMechanism,
    cols: Columns,
    run: pkm::analysis::motion::MotionRun,
) -> PyResult<Bound<'py, PyDict>> {
    let (p, a) = (m.coordinates().len(), m.actuators().len());
    let d = PyDict::new(py);
    d.set_item("t", vec1(py, cols.t))?;
    d.set_item("line", vec1(py, cols.line))?;
    d.set_item("x", vec2(py, cols.x, p)?)?;
    d.set_item("q", vec2(py, cols.q, a)?)?;
    d.set_item("qd", vec2(py, cols.qd, a)?)?;
    d.set_item("qdd", vec2(py, cols.qdd, a)?)?;
    d.set_item(
        "columns",
        (
            m.coordinates()
                .iter()
                .map(|c| c.name.clone())
                .collect::<Vec<_>>(),
            m.actuators()
                .iter()
                .map(|c| c.name.clone())
                .collect::<Vec<_>>(),
        ),
    )?;
    d.set_item("summary", summary(py, &run.summary)?)?;
    d.set_item("notes", run.notes)?;
    Ok(d)
}

/// The sampling asked for: `rate` (Hz) or `points` per move, 1000 Hz by default.
fn sampling(rate: Option<f64>, points: Option<usize>) -> PyResult<pkm::motion::Sampling> {
    Ok(match (positive("rate", rate)?, points) {
        (Some(_), Some(_)) => return Err(invalid("rate", "give rate or points, not both")),
        (_, Some(n)) if n < 2 => return Err(invalid("points", "expected at least 2")),
        (_, Some(n)) => pkm::motion::Sampling::Points(n),
        (Some(r), None) => pkm::motion::Sampling::Rate(r),
        (None, None) => pkm::motion::Sampling::Rate(1000.0),
    })
}

/// The program's text or the waypoints; the library's source is built on the worker
/// side of `detach` (a boxed reader is not Send).
enum Src {
    Program(String),
    Waypoints(Vec<Vec<f64>>),
}

impl Src {
    /// The program of `gcode` (its text, or a path to it) or the waypoints of `path`
    /// (rows of `p` coordinates): exactly one of them.
    fn of(
        gcode: Option<&Bound<'_, PyAny>>,
        path: Option<&Bound<'_, PyAny>>,
        p: usize,
    ) -> PyResult<Src> {
        Ok(match (gcode, path) {
            (Some(g), None) => Src::Program(if let Ok(s) = g.extract::<String>() {
                s
            } else {
                let f: std::path::PathBuf = g
                    .extract()
                    .map_err(|_| invalid("gcode", "expected the program's text or a path"))?;
                std::fs::read_to_string(&f)
                    .map_err(|e| invalid("gcode", format!("cannot read {}: {e}", f.display())))?
            }),
            (None, Some(w)) => {
                let (v, _) = rows(w, p, "path")?;
                Src::Waypoints(v.chunks_exact(p).map(<[f64]>::to_vec).collect())
            }
            _ => return Err(invalid("motion", "give either gcode or path")),
        })
    }

    /// The library's motion source, a program starting at `from` with `tool_length`.
    fn into_source(
        self,
        from: Option<Vec<f64>>,
        tool_length: Option<f64>,
    ) -> pkm::analysis::motion::MotionSource<'static> {
        use pkm::analysis::motion::{MotionSource, ProgramSetup};
        match self {
            Src::Program(text) => MotionSource::Gcode {
                reader: Box::new(std::io::Cursor::new(text.into_bytes())),
                from,
                setup: Box::new(ProgramSetup {
                    tool_length,
                    ..Default::default()
                }),
            },
            Src::Waypoints(points) => MotionSource::Polyline { points },
        }
    }
}

/// The run's summary as a dict, its per-axis statistics as {name: stats}, as `pkm
/// motion` writes them.
fn summary<'py>(py: Python<'py>, run: &pkm::motion::MotionSummary) -> PyResult<Bound<'py, PyDict>> {
    let summary = convert::to_py(py, run)?.cast_into::<PyDict>()?;
    for key in ["actuators", "serial"] {
        if let Some(list) = summary.get_item(key)? {
            let named = PyDict::new(py);
            for item in list.try_iter()? {
                let item = item?;
                named.set_item(item.get_item(0)?, item.get_item(1)?)?;
            }
            summary.set_item(key, named)?;
        }
    }
    Ok(summary)
}
