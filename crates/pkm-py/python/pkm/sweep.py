"""Design sweeps: many candidate machines of one family, each judged by the same
objectives, on one machine or on a Dask cluster.

A sweep is three things:

* a **space** of design parameters, as a pandas DataFrame with one row per candidate
  (:func:`grid`, :func:`latin_hypercube`, :func:`sobol`);
* a **build** function turning one row (a dict of parameter values) into a machine:
  a dict shaped like a machine file (see ``pkm.Machine.from_dict``), TOML text, or a
  ``pkm.Machine``;
* the **objectives** (:class:`Objectives`): reachable share and volume of a required
  box or cylinder, worst condition number inside it, peak actuator speed along a
  reference G-code program, and an accuracy bound from given tolerances.

:func:`run` evaluates every candidate and returns the space with one column per
objective (and ``error`` for candidates pkm refused, with pkm's message). With a
``client`` (``dask.distributed.Client``: a ``LocalCluster``'s or a multi-node
cluster's, from its scheduler address) the candidates go out in batches, one Dask task
per batch, so the per-task overhead (about a millisecond) stays small against the
batch's work; without one they run in this process. Both give the same table.

:func:`pareto_front` marks the non-dominated candidates and :func:`plot_pareto` draws
them; :func:`write_parquet` writes the table whole (temporary file, then rename).

Units: mm, rad, s, as everywhere in pkm's Python API; the objectives taken from
summaries keep the summaries' units (a revolute actuator's speed in deg/s).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from typing import Any, Callable, Iterable, Optional, Sequence, Union

import numpy as np

import pkm

Build = Callable[[dict], Union[dict, str, "pkm.Machine"]]

def _extra(module: str, what: str):
    """``module`` imported, or an ImportError saying it comes with the ``sweep``
    extra: ``pkm.sweep`` needs Dask, pandas, pyarrow, matplotlib and scipy, which a
    plain ``pip install pkm`` leaves out."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as e:
        top = module.split(".")[0]
        raise ImportError(
            f"pkm.sweep needs {top} for {what}: install the sweep extra, "
            f"pip install 'pkm[sweep]' (from a clone: pip install './crates/pkm-py[sweep]')"
        ) from e


# -- parameter spaces -------------------------------------------------------------


def _frame(columns: Sequence[str], values: np.ndarray):
    pd = _extra("pandas", "its tables")

    return pd.DataFrame(values, columns=list(columns))


def grid(parameters: dict[str, Sequence[float]]):
    """Every combination of the given values: ``{"base_radius": [400, 500, 600],
    ...}``; the first parameter varies slowest."""
    names = list(parameters)
    axes = [np.asarray(parameters[n], dtype=float) for n in names]
    if any(a.ndim != 1 or a.size == 0 for a in axes):
        raise pkm.InvalidInputError("grid: every parameter needs a non-empty list of values")
    mesh = np.meshgrid(*axes, indexing="ij")
    return _frame(names, np.stack([m.ravel() for m in mesh], axis=1))


def _bounds(parameters: dict[str, tuple[float, float]]):
    names = list(parameters)
    lo = np.array([float(parameters[n][0]) for n in names])
    hi = np.array([float(parameters[n][1]) for n in names])
    if not (np.isfinite(lo).all() and np.isfinite(hi).all() and (hi >= lo).all()):
        raise pkm.InvalidInputError("bounds: expected finite (low, high) with low <= high")
    return names, lo, hi


def latin_hypercube(parameters: dict[str, tuple[float, float]], n: int, seed: int = 1):
    """``n`` candidates by Latin hypercube sampling of ``{name: (low, high)}``
    (scipy.stats.qmc, reproducible by ``seed``)."""
    qmc = _extra("scipy.stats.qmc", "Latin hypercube sampling")

    names, lo, hi = _bounds(parameters)
    u = qmc.LatinHypercube(d=len(names), seed=seed).random(n)
    return _frame(names, qmc.scale(u, lo, hi) if len(names) else u)


def sobol(parameters: dict[str, tuple[float, float]], n: int, seed: int = 1):
    """``n`` candidates of a scrambled Sobol sequence over ``{name: (low, high)}``
    (scipy.stats.qmc; ``n`` a power of two keeps its balance properties)."""
    qmc = _extra("scipy.stats.qmc", "Sobol sequences")

    names, lo, hi = _bounds(parameters)
    u = qmc.Sobol(d=len(names), scramble=True, seed=seed).random(n)
    return _frame(names, qmc.scale(u, lo, hi))


# -- objectives -------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Objectives:
    """What each candidate is judged by (every field optional).

    Required region, at ``orientation`` (pose angles, rad; default the machine's home
    orientation):

    * ``box``: ``((xmin, xmax), (ymin, ymax), (zmin, zmax))`` (mm), or
    * ``cylinder``: ``(x, y, radius, zmin, zmax)`` (mm), axis along Z,

    on a grid from face to face (both included), points at most ``step`` apart,

    gives ``reachable_fraction`` (share of its points within every limit),
    ``reachable_volume_mm3`` (that share of its volume) and ``worst_condition`` (the
    largest condition number over its reachable points).

    ``gcode`` (program text) run at ``feed`` (mm/s; None: the program's F words)
    from ``start`` (default home), sampled at ``rate`` Hz, gives
    ``peak_actuator_speed`` (the largest actuator speed as ``pkm motion``'s summary
    gives it: mm/s, deg/s for revolute actuators),
    ``program_violations`` (limit violations along it) and
    ``feed_override_max``.

    ``stiffness=True`` (the drives' ``stiffness`` in the machine) gives
    ``min_stiffness_n_per_um``: the smallest stiffness of the tool tip against a force
    over the region's reachable points (``Machine.stiffness``, N/um).

    ``tolerances`` (one per kind, as ``Machine.errors``: ``joint``, ``length``,
    ``zero`` in mm, ``angle`` in rad) gives ``accuracy_worst_mm``: the worst-case
    position error over the region's centre and corners (its centre alone without a
    region).
    """

    box: Optional[tuple] = None
    cylinder: Optional[tuple] = None
    step: float = 10.0
    orientation: Optional[Sequence[float]] = None
    gcode: Optional[str] = None
    feed: Optional[float] = None
    rate: float = 250.0
    start: Optional[Sequence[float]] = None
    tolerances: Optional[dict] = None
    stiffness: bool = False

    def region(self, m: "pkm.Machine") -> Optional[np.ndarray]:
        """The required region's poses (N, P) on this machine, or None."""
        if self.box is None and self.cylinder is None:
            return None
        if not (self.step > 0 and math.isfinite(self.step)):
            raise pkm.InvalidInputError("step: expected a positive number of mm")
        def axis(a, b):
            # From face to face, both included, at most `step` apart.
            if not (math.isfinite(a) and math.isfinite(b) and b >= a):
                raise pkm.InvalidInputError(f"region: expected min <= max, got {a}, {b}")
            return np.linspace(a, b, max(2, math.ceil((b - a) / self.step - 1e-9) + 1))

        if self.box is not None:
            (x0, x1), (y0, y1), (z0, z1) = self.box
            axes = [axis(a, b) for a, b in ((x0, x1), (y0, y1), (z0, z1))]
            pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        else:
            cx, cy, r, z0, z1 = self.cylinder
            grid = [axis(cx - r, cx + r), axis(cy - r, cy + r), axis(z0, z1)]
            pts = np.stack(np.meshgrid(*grid, indexing="ij"), axis=-1).reshape(-1, 3)
            pts = pts[(pts[:, 0] - cx) ** 2 + (pts[:, 1] - cy) ** 2 <= r * r * (1 + 1e-12)]
        if len(pts) > 5_000_000:
            raise pkm.InvalidInputError(
                f"region: {len(pts)} points at step {self.step} mm; at most 5e6 (raise the step)")
        poses = np.tile(m.home, (len(pts), 1))
        poses[:, :3] = pts
        if self.orientation is not None and poses.shape[1] == 6:
            poses[:, 3:6] = np.asarray(self.orientation, dtype=float)
        return poses

    def volume(self) -> float:
        """The required region's volume (mm^3)."""
        if self.box is not None:
            return float(np.prod([b - a for a, b in self.box]))
        if self.cylinder is not None:
            _, _, r, z0, z1 = self.cylinder
            return math.pi * r * r * (z1 - z0)
        return float("nan")

    def columns(self) -> list[str]:
        """The objective columns this set of objectives writes."""
        cols = []
        if self.box is not None or self.cylinder is not None:
            cols += ["reachable_fraction", "reachable_volume_mm3", "worst_condition"]
        if self.gcode is not None:
            cols += ["peak_actuator_speed", "program_violations", "feed_override_max"]
        if self.tolerances is not None:
            cols += ["accuracy_worst_mm"]
        if self.stiffness:
            cols += ["min_stiffness_n_per_um"]
        return cols


def _machine(built) -> "pkm.Machine":
    if isinstance(built, pkm.Machine):
        return built
    if isinstance(built, str):
        return pkm.Machine.from_toml(built, "<candidate>")
    if isinstance(built, dict):
        return pkm.Machine.from_dict(built, "<candidate>")
    raise pkm.InvalidInputError(
        f"build: expected a dict, TOML text or pkm.Machine, got {type(built).__name__}")


def evaluate(m: "pkm.Machine", objectives: Objectives) -> dict[str, Any]:
    """The objectives of one machine (a dict of column -> value)."""
    out: dict[str, Any] = {}
    region = objectives.region(m)
    if region is not None:
        b = m.ik(region)
        ok = b.reachable
        share = float(ok.mean()) if len(ok) else 0.0
        out["reachable_fraction"] = share
        out["reachable_volume_mm3"] = share * objectives.volume()
        out["worst_condition"] = float(m.condition(region[ok]).max()) if ok.any() else float("nan")
        if objectives.stiffness:
            k = m.stiffness(region[ok])["smallest_n_per_um"] if ok.any() else np.array([])
            out["min_stiffness_n_per_um"] = float(np.nanmin(k)) if np.isfinite(k).any() else float("nan")
    elif objectives.stiffness:
        raise pkm.InvalidInputError("stiffness: needs a required region (box or cylinder)")
    if objectives.gcode is not None:
        # The summary alone: constant memory whatever the program's length.
        s = m.motion(gcode=objectives.gcode, feed=objectives.feed, rate=objectives.rate,
                     start=objectives.start, samples=False)["summary"]
        peaks = [a["peak_velocity"] for a in s["actuators"].values()]
        out["peak_actuator_speed"] = float(max(peaks)) if peaks else 0.0
        out["program_violations"] = len(s["violations"]) + int(s["violations_not_listed"])
        f = s.get("feed_override_max")
        out["feed_override_max"] = float(f) if f is not None else float("nan")
    if objectives.tolerances is not None:
        if region is not None:
            lo, hi = region[:, :3].min(axis=0), region[:, :3].max(axis=0)
            corners = [np.where([i & 1, i & 2, i & 4], hi, lo) for i in range(8)]
            points = [(lo + hi) / 2, *corners]
            base = region[0]
        else:
            base = m.home
            points = [base[:3]]
        worst = 0.0
        for p in points:
            x = base.copy()
            x[:3] = p
            e = m.errors(x, tolerances=objectives.tolerances)
            worst = max(worst, float(e["budget"]["worst_case"]))
        out["accuracy_worst_mm"] = worst
    return out


def evaluate_batch(build: Build, rows: list[dict], objectives: Objectives) -> list[dict]:
    """Builds and evaluates the candidates of one batch (one Dask task). A candidate pkm
    refuses (an invalid geometry, a program it cannot run) gets NaN objectives and
    pkm's message in ``error``; any other exception propagates."""
    cols = objectives.columns()
    results = []
    for row in rows:
        t0 = time.perf_counter()
        rec = {c: float("nan") for c in cols}
        rec["error"] = None
        try:
            rec.update(evaluate(_machine(build(dict(row))), objectives))
        except pkm.Error as e:
            rec["error"] = f"{type(e).__name__}: {e}"
        rec["seconds"] = time.perf_counter() - t0
        results.append(rec)
    return results


def batches(n: int, size: int) -> list[range]:
    """Row ranges of ``size`` (the last shorter)."""
    return [range(i, min(i + size, n)) for i in range(0, n, size)]


def default_batch_size(n: int, workers: int) -> int:
    """About four tasks per worker (load balance) and at most 64 candidates a task."""
    return max(1, min(64, math.ceil(n / (4 * max(1, workers)))))


def run(build: Build, space, objectives: Objectives, client=None,
        batch_size: Optional[int] = None, progress: Optional[Callable[[int, int], None]] = None):
    """Evaluates every row of ``space`` (a DataFrame of design parameters).

    ``client``: a ``dask.distributed.Client`` (``LocalCluster`` or a remote
    scheduler); None runs here. ``batch_size``: candidates per Dask task (default
    :func:`default_batch_size`). ``progress(done, total)`` is called as batches
    finish. Returns ``space`` with the objective columns, ``error`` and ``seconds``
    (evaluation time per candidate), in the rows' order.
    """
    pd = _extra("pandas", "its tables")

    rows = space.to_dict("records")
    n = len(rows)
    if n == 0:
        raise pkm.InvalidInputError("space: no candidate")
    if client is None:
        workers = 1
    else:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
    size = batch_size or default_batch_size(n, workers)
    parts = batches(n, size)
    results: list[Optional[list[dict]]] = [None] * len(parts)
    if client is None:
        for k, r in enumerate(parts):
            results[k] = evaluate_batch(build, [rows[i] for i in r], objectives)
            if progress:
                progress(r.stop, n)
    else:
        from dask.distributed import as_completed

        futures = client.map(evaluate_batch, [build] * len(parts),
                             [[rows[i] for i in r] for r in parts],
                             [objectives] * len(parts), pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        done = 0
        for f in as_completed(futures):
            k = index[f.key]
            results[k] = f.result()
            done += len(parts[k])
            if progress:
                progress(done, n)
    flat = [rec for part in results for rec in part]
    return pd.concat([space.reset_index(drop=True), pd.DataFrame(flat)], axis=1)


def local_cluster(workers: int, threads_per_worker: int = 1):
    """A ``dask.distributed`` ``LocalCluster`` of ``workers`` processes and its
    ``Client``. Each worker's pkm runs on ``threads_per_worker`` threads
    (RAYON_NUM_THREADS), so candidates, not poses, share the cores."""
    from dask.distributed import Client, LocalCluster

    # Set in the workers' environment only: this process keeps all its cores.
    cluster = LocalCluster(n_workers=workers, threads_per_worker=threads_per_worker,
                           processes=True, dashboard_address=None,
                           env={"RAYON_NUM_THREADS": str(threads_per_worker)})
    return Client(cluster)


# -- results ----------------------------------------------------------------------


def pareto_front(table, objectives: dict[str, str]) -> np.ndarray:
    """Whether each row is non-dominated for ``{column: "min" | "max"}`` (rows with an
    error or a NaN objective are never on the front)."""
    cols = list(objectives)
    for c, sense in objectives.items():
        if sense not in ("min", "max"):
            raise pkm.InvalidInputError(f"pareto_front: `{c}`: expected min or max, got {sense}")
    v = np.column_stack([
        table[c].to_numpy(dtype=float) * (1.0 if objectives[c] == "min" else -1.0) for c in cols
    ])
    valid = np.isfinite(v).all(axis=1)
    if "error" in table:
        valid &= table["error"].isna().to_numpy()
    front = valid.copy()
    for i in np.flatnonzero(valid):
        others = v[valid]
        dominated = (others <= v[i]).all(axis=1) & (others < v[i]).any(axis=1)
        if dominated.any():
            front[i] = False
    return front


def plot_pareto(table, x: str, y: str, front: np.ndarray, path: Union[str, os.PathLike],
                title: Optional[str] = None, color: Optional[str] = None):
    """Scatter of every candidate (``x`` against ``y``; coloured by ``color`` when
    given), the Pareto front highlighted and joined; written to ``path`` (SVG, PNG,
    PDF by its suffix) whole."""
    matplotlib = _extra("matplotlib", "its plots")

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5), dpi=120)
    ok = table["error"].isna().to_numpy() if "error" in table else np.ones(len(table), bool)
    kw = {}
    if color is not None:
        kw = {"c": table[color][ok], "cmap": "viridis"}
    sc = ax.scatter(table[x][ok], table[y][ok], s=12, alpha=0.6, **kw)
    if color is not None:
        fig.colorbar(sc, ax=ax, label=color)
    f = table[front].sort_values(x)
    ax.plot(f[x], f[y], "-o", color="crimson", ms=5, lw=1.2,
            label=f"Pareto front ({len(f)} of {int(ok.sum())})")
    if (~ok).any():
        ax.set_title((title or "") + f"  ({int((~ok).sum())} candidates refused)")
    elif title:
        ax.set_title(title)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    _atomic(path, lambda tmp: fig.savefig(tmp, format=os.path.splitext(str(path))[1][1:] or "svg"))
    plt.close(fig)


def write_parquet(table, path: Union[str, os.PathLike]):
    """The table as Parquet, written whole (temporary file, then rename)."""
    _atomic(path, lambda tmp: table.to_parquet(tmp, index=False))


def _atomic(path, write):
    path = os.fspath(path)
    tmp = f"{path}.tmp-{os.getpid()}"
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
