"""Sweep a family of hexapods on Dask and keep the Pareto-optimal designs.

The family: six base joints in three pairs on a circle of radius ``base_radius``,
``base_gap`` (deg) apart within a pair; six platform joints likewise
(``platform_radius``, ``platform_gap``), turned 60 deg against the base; struts of
``stroke`` mm whose mid-stroke puts the platform level at Z = 650 mm. Each candidate is
judged by:

* the share and volume of a required box (X, Y within +-200 mm, Z 550..750 mm) it
  reaches within every limit, and its worst condition number there;
* the peak strut speed along a reference program (a circle and two tilts);
* the worst-case position error over the box's centre and corners for +-10 um on
  joints, links and zero lengths.

Run:  python examples/python/sweep_hexapod.py --workers 2 --quick --out sweep-out
      python examples/python/sweep_hexapod.py --scheduler tcp://HOST:8786 --samples 4096

Writes OUT/sweep.parquet (one row per candidate, ``pareto`` marks the front over all
four objectives) and OUT/pareto.svg (volume against worst condition).
"""

import argparse
import math
import pathlib
import sys
import time

import numpy as np

import pkm
from pkm import sweep

HOME_Z = 650.0

PROGRAM = """\
(reference program: circle of 100 mm, then tilts; pkm.sweep example)
G21 G90 G17
G0 X100 Y0 Z650
G1 Z620 F3000
G3 X100 Y0 I-100 J0 F6000
G1 X0 Y0 Z700 A5 F3000
G1 B-5
G1 A0 B0 Z650
"""

SPACE = {
    "base_radius": (350.0, 700.0),
    "platform_radius": (120.0, 350.0),
    "base_gap": (10.0, 60.0),
    "platform_gap": (10.0, 60.0),
    "stroke": (250.0, 500.0),
}


def hexapod(p: dict) -> dict:
    """The machine file (as a dict) of one candidate."""
    rb, rp = p["base_radius"], p["platform_radius"]
    gb, gp = math.radians(p["base_gap"]), math.radians(p["platform_gap"])

    def on_circle(r, a):
        return [r * math.cos(a), r * math.sin(a), 0.0]

    base, plat = {}, {}
    for k in range(3):
        c = math.radians(90 + 120 * k)
        base[f"B{2 * k + 1}"] = on_circle(rb, c - gb / 2)
        base[f"B{2 * k + 2}"] = on_circle(rb, c + gb / 2)
        c60 = c + math.radians(60)
        plat[f"P{2 * k + 1}"] = on_circle(rp, c60 - gp / 2)
        plat[f"P{2 * k + 2}"] = on_circle(rp, c60 + gp / 2)
    # Strut 2k+1 from the pair's second base joint to the next platform pair's first
    # joint; strut 2k+2 from the next base pair's first joint to its second.
    pairs = []
    for k in range(3):
        pairs.append((f"B{2 * k + 2}", f"P{2 * k + 1}"))
        pairs.append((f"B{(2 * k + 2) % 6 + 1}", f"P{2 * k + 2}"))
    b, q = np.array(base[pairs[0][0]]), np.array(plat[pairs[0][1]])
    horizontal = np.linalg.norm(b[:2] - q[:2])
    mid = math.hypot(horizontal, HOME_Z)
    lo = mid - p["stroke"] / 2
    struts = [
        {"name": str(i + 1), "base": bj, "platform": pj,
         "length": [lo, lo + p["stroke"]], "max_velocity": 500.0, "max_acceleration": 5000.0}
        for i, (bj, pj) in enumerate(pairs)
    ]
    return {
        "type": "hexapod",
        "name": "sweep candidate",
        "base_joints": base,
        "platform_joints": plat,
        "struts": struts,
        "tool": {"tip": [0.0, 0.0, 0.0]},
        "limits": {"base_joint_max_angle": 50.0, "platform_joint_max_angle": 50.0,
                   "strut_diameter": 30.0},
        "home": {"position": [0.0, 0.0, HOME_Z], "angles": [0.0, 0.0, 0.0]},
    }


def objectives(quick: bool) -> sweep.Objectives:
    return sweep.Objectives(
        box=((-200.0, 200.0), (-200.0, 200.0), (550.0, 750.0)),
        step=30.0 if quick else 10.0,
        gcode=PROGRAM,
        rate=100.0 if quick else 500.0,
        tolerances={"joint": 0.01, "length": 0.01, "zero": 0.01, "angle": 1e-5},
    )


FRONT = {
    "reachable_volume_mm3": "max",
    "worst_condition": "min",
    "peak_actuator_speed": "min",
    "accuracy_worst_mm": "min",
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2,
                    help="local Dask workers (0: run in this process)")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786)")
    ap.add_argument("--samples", type=int, default=256, help="candidates (Latin hypercube)")
    ap.add_argument("--quick", action="store_true",
                    help="16 candidates, a 30 mm grid, 100 Hz sampling")
    ap.add_argument("--batch-size", type=int, help="candidates per Dask task")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default="sweep-out", help="output directory")
    a = ap.parse_args(argv)

    n = 16 if a.quick else a.samples
    space = sweep.latin_hypercube(SPACE, n, seed=a.seed)
    obj = objectives(a.quick)
    client = None
    if a.scheduler:
        from dask.distributed import Client
        client = Client(a.scheduler)
    elif a.workers > 0:
        client = sweep.local_cluster(a.workers)

    def progress(done, total):
        print(f"\r{done}/{total} candidates", end="", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    table = sweep.run(hexapod, space, obj, client=client, batch_size=a.batch_size,
                      progress=progress)
    wall = time.perf_counter() - t0
    print(file=sys.stderr)
    if client is not None:
        client.close()

    table["pareto"] = sweep.pareto_front(table, FRONT)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    sweep.write_parquet(table, out / "sweep.parquet")
    front2 = sweep.pareto_front(table, {"reachable_volume_mm3": "max", "worst_condition": "min"})
    sweep.plot_pareto(table, "worst_condition", "reachable_volume_mm3", front2,
                      out / "pareto.svg", title="hexapod family", color="peak_actuator_speed")

    refused = int(table["error"].notna().sum())
    per = table["seconds"].median()
    print(f"{len(table)} candidates in {wall:.2f} s ({refused} refused); median "
          f"{per * 1e3:.1f} ms per candidate; {int(table['pareto'].sum())} on the Pareto front")
    cols = ["base_radius", "platform_radius", "stroke", *FRONT]
    print(table[table["pareto"]][cols].sort_values("reachable_volume_mm3", ascending=False)
          .head(8).to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    print(f"wrote {out / 'sweep.parquet'} and {out / 'pareto.svg'}")


if __name__ == "__main__":
    try:
        main()
    except ImportError as e:
        # Dask, pandas, scipy... come with pkm's `sweep` extra: say so, no traceback.
        sys.exit(f"error: {e}")
