"""Speed of pkm's Python package, and of Pinocchio and the Robotics Toolbox on the same
6R robot in the same run. Not a test: a script that prints medians.

    target/py-venv/bin/pip install pin roboticstoolbox-python   # the peers, optional
    target/py-venv/bin/python crates/pkm-py/bench/bench_pkm.py [--quick]

Inputs are like a user's: random poses uniform in +-100 mm and +-10 deg about the
LinuxCNC hexapod's home; random joint vectors uniform in +-pi for the UR5-class robot
(examples/robots/ur5-like.urdf, which pkm, Pinocchio and the Robotics Toolbox all load).
Every timing is the median of several rounds; thread counts are printed (pkm's batches
use rayon on all cores unless RAYON_NUM_THREADS says otherwise; its single calls and
the peers' loops run on one thread).
"""

import argparse
import os
import pathlib
import platform
import statistics
import sys
import time

import numpy as np

import pkm

ROOT = pathlib.Path(__file__).resolve().parents[3]
HEX = ROOT / "examples" / "machines" / "hexapod-linuxcnc.toml"
UR5 = ROOT / "examples" / "robots" / "ur5-like.urdf"


def median_time(f, rounds):
    times = []
    for _ in range(rounds):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def per_call(f, args, rounds):
    """Median over rounds of the time per call of f over args (seconds)."""
    def loop():
        for a in args:
            f(a)
    return median_time(loop, rounds) / len(args)


def row(what, seconds, unit="ms", extra=""):
    scale = {"ms": 1e3, "us": 1e6, "ns": 1e9}[unit]
    print(f"  {what:<62} {seconds * scale:10.3f} {unit} {extra}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer rounds and rows")
    a = ap.parse_args()
    rounds = 3 if a.quick else 9
    n = 100_000 if a.quick else 1_000_000
    threads = os.environ.get("RAYON_NUM_THREADS", f"all ({os.cpu_count()})")
    print(f"pkm {pkm.__version__}, Python {platform.python_version()}, numpy {np.__version__}, "
          f"{os.cpu_count()} CPUs, rayon threads: {threads}")

    print(f"\nHexapod (LinuxCNC genhexkins geometry), {n:.0e} random poses:")
    m = pkm.load(HEX)
    rng = np.random.default_rng(1)
    x = m.home + np.column_stack([rng.uniform(-100, 100, (n, 3)),
                                  rng.uniform(-np.radians(10), np.radians(10), (n, 3))])
    r = m.ik(x)
    row("m.ik(poses): IK + every limit, mask, violated limit", median_time(lambda: m.ik(x), rounds),
        extra=f"({r.reachable.mean():.1%} reachable)")
    row("m.ik(poses, check=False): IK only", median_time(lambda: m.ik(x, check=False), rounds))
    q = r.actuators[r.reachable][: n // 10]
    row(f"m.fk({len(q)} actuator sets) from home", median_time(lambda: m.fk(q), rounds))
    row("m.condition(poses)", median_time(lambda: m.condition(x[: n // 10]), rounds),
        extra=f"({n // 10} poses)")
    one = [x[i] for i in range(20_000 if a.quick else 100_000)]
    row("m.ik(pose), one pose per call (with limits)", per_call(m.ik, one, rounds), "us")
    row("m.ik(pose, check=False), one pose per call", per_call(lambda p: m.ik(p, check=False), one, rounds), "us")

    print("\n6R robot (UR5-class URDF), random joints, one call per configuration:")
    robot = pkm.load(UR5)
    k = 2_000 if a.quick else 20_000
    qs = rng.uniform(-np.pi, np.pi, (k, 6))
    batch = robot.fk(qs)
    row(f"pkm   m.fk(Q) batch of {k} (pose X..C)", median_time(lambda: robot.fk(qs), rounds) / k, "us",
        "per configuration")
    row("pkm   m.fk(q) per call", per_call(robot.fk, list(qs), rounds), "us")
    xs = batch.poses
    row("pkm   m.jacobian(pose) per call (IK Jacobian)", per_call(robot.jacobian, list(xs), rounds), "us")
    try:
        import pinocchio as pin

        model = pin.buildModelFromUrdf(str(UR5))
        data = model.createData()
        fid = model.getFrameId("tool0")

        def pin_fk(qv):
            pin.forwardKinematics(model, data, qv)
            pin.updateFramePlacement(model, data, fid)
            return data.oMf[fid]

        def pin_jac(qv):
            return pin.computeFrameJacobian(model, data, qv, fid, pin.LOCAL_WORLD_ALIGNED)

        row(f"Pinocchio {pin.__version__} forwardKinematics + frame placement", per_call(pin_fk, list(qs), rounds), "us")
        row("Pinocchio computeFrameJacobian", per_call(pin_jac, list(qs), rounds), "us")
        diff = max(np.abs(pin_fk(qv).translation * 1000 - xv[:3]).max() for qv, xv in zip(qs[:200], xs[:200]))
        print(f"  (tool positions pkm vs Pinocchio: largest difference {diff:.2e} mm over 200 configurations)")
    except ImportError:
        print("  Pinocchio not installed (pip install pin): skipped")
    try:
        import warnings

        import roboticstoolbox as rtb

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rob = rtb.Robot.URDF(str(UR5))
        row(f"Robotics Toolbox {rtb.__version__} fkine", per_call(rob.fkine, list(qs[:2000]), rounds), "us")
        row("Robotics Toolbox jacob0", per_call(rob.jacob0, list(qs[:2000]), rounds), "us")
        diff = max(np.abs(rob.fkine(qv).t * 1000 - xv[:3]).max() for qv, xv in zip(qs[:200], xs[:200]))
        print(f"  (tool positions pkm vs Robotics Toolbox: largest difference {diff:.2e} mm over 200 configurations)")
    except ImportError:
        print("  Robotics Toolbox not installed (pip install roboticstoolbox-python): skipped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
