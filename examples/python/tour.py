# %% [markdown]
# # A tour of pkm from Python
#
# Notebook-style (`# %%` cells: open it in Jupyter with jupytext, VS Code or Spyder,
# or run it as a script from the repository root). Arrays are in mm and rad.

# %%
import pathlib

import numpy as np

import pkm

ROOT = pathlib.Path(__file__).resolve().parents[2] if "__file__" in globals() else pathlib.Path(".")
m = pkm.load(ROOT / "examples/machines/hexapod-linuxcnc.toml")
print(m)
print([c["name"] + " " + c["unit"] for c in m.coordinates])

# %% [markdown]
# ## Inverse kinematics of a million poses, every limit checked

# %%
rng = np.random.default_rng(1)
n = 1_000_000
poses = m.home + np.column_stack([
    rng.uniform(-100, 100, (n, 3)),             # mm
    rng.uniform(-np.radians(10), np.radians(10), (n, 3)),  # rad
])
q, reachable, limit = m.ik(poses)
print(f"{reachable.mean():.1%} reachable")
names, counts = np.unique(limit[~reachable], return_counts=True)
r = m.ik(poses)
for k, c in sorted(zip(names, counts), key=lambda t: -t[1])[:3]:
    print(f"{c:7d} poses stopped by {r.limit_names[k]}")
print(r.messages()[int(np.flatnonzero(~reachable)[0])])

# %% [markdown]
# ## Forward kinematics back, and the Jacobian

# %%
f = m.fk(q[reachable][:1000])
print("round trip:", np.abs(f.poses - poses[reachable][:1000]).max(), "mm/rad")
J = m.jacobian(m.home)
print("condition at home:", m.condition(m.home), "singular values:", np.linalg.svd(J)[1].round(3))

# %% [markdown]
# ## Workspace, motion, accuracy

# %%
w = m.workspace(bounds=[[-200, 200], [-200, 200], [450, 650]], step=20.0)
print(f"reachable {w['summary']['reachable']} of {w['summary']['points']} points, "
      f"volume {w['summary']['volume_mm3'] / 1e6:.1f} dm^3 (grid cells)")

program = "G21 G90\nG0 X100 Y0 Z508\nG3 X100 Y0 I-100 J0 F6000\n"
run = m.motion(gcode=program, rate=1000)
peak = {k: round(v["peak_velocity"], 1) for k, v in run["summary"]["actuators"].items()}
print(f"{len(run['t'])} samples; peak strut speeds (mm/s): {peak}")

e = m.errors(tolerances={"joint": 0.01, "length": 0.01, "zero": 0.01, "angle": 1e-5})
print(f"worst-case position error at home: {e['budget']['worst_case'] * 1000:.1f} um")

# %% [markdown]
# ## Identify a machine from (simulated) measurements

# %%
s = pkm.simulate_measurements(m, states=40, holdout=10, seed=2)
c = pkm.calibrate(m, s["measurements"], validation=s["validation"])
v = c["validation"]
print(f"held-out point error: nominal {v['nominal']['rms'] * 1000:.1f} um rms, "
      f"identified {v['identified']['rms'] * 1000:.2f} um rms")
