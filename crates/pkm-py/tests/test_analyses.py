"""The analyses from Python equal the pkm command's results on the example machines;
identification recovers a simulated machine."""

import csv
import json
import math
import pathlib

import numpy as np
import pytest

import pkm
from conftest import ROOT, cli, example

TRIPOD = example("tripod-seed000.toml")
HEX = example("hexapod-seed001.toml")
ARC = str(ROOT / "examples" / "paths" / "seed000-arc.ngc")


def test_workspace_equals_the_command(tmp_path):
    w = pkm.load(TRIPOD).workspace()
    cli("workspace", TRIPOD, "--out", str(tmp_path))
    s = json.loads((tmp_path / "summary.json").read_text())
    assert w["summary"]["reachable"] == s["reachable"]
    assert w["summary"]["points"] == s["points"]
    assert w["summary"]["volume_mm3"] == pytest.approx(s["volume_mm3"], rel=1e-12)
    assert w["grid"] == s["grid_bounds"]
    n = s["points"]
    assert w["points"].shape == (n, 3) and w["reachable"].sum() == s["reachable"]
    assert np.isnan(w["condition"][~w["reachable"]]).all()
    assert (w["condition"][w["reachable"]] >= 1).all()
    # Every unreachable point names its binding limit, every reachable one none.
    assert ((w["binding"] >= 0) == ~w["reachable"]).all()
    counts = {}
    for b in w["binding"][w["binding"] >= 0]:
        counts[w["binding_names"][b]] = counts.get(w["binding_names"][b], 0) + 1
    assert counts == s["binding"]


def test_workspace_with_bounds_and_step_in_mm():
    m = pkm.load(TRIPOD)
    w = m.workspace(bounds=[[-40, 40], [-40, 40], [-300, -280]], step=10.0)
    assert [a["count"] for a in w["axes"]] == [9, 9, 3]
    assert w["points"][:, 0].min() == -40 and w["points"][:, 2].max() == -280
    # Each point's reachability is the inverse kinematics' with its limits.
    x = np.tile(m.home, (len(w["points"]), 1))
    x[:, :3] = w["points"]
    assert np.array_equal(m.ik(x).reachable, w["reachable"])


def test_motion_of_a_program_equals_the_command(tmp_path):
    m = pkm.load(TRIPOD)
    r = m.motion(gcode=pathlib.Path(ARC), start=[32, -32, -290, 0, 0, 0], feed=10000 / 60, points=101)
    cli("motion", TRIPOD, "--gcode", ARC, "--from", "32,-32,-290", "--feed", "10000",
        "--points", "101", "--out", str(tmp_path))
    s = json.loads((tmp_path / "summary.json").read_text())
    assert r["summary"]["samples"] == s["samples"] == len(r["t"])
    for name, st in s["actuators"].items():
        assert r["summary"]["actuators"][name]["peak_velocity"] == pytest.approx(
            st["peak_velocity"], rel=1e-12)
    with open(tmp_path / "actuators.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(r["t"])
    for i in (0, 50, 100):
        assert float(rows[i]["t_s"]) == pytest.approx(r["t"][i], abs=1e-6)
        for k, a in enumerate(r["columns"][1]):
            assert float(rows[i][f"{a}_mm"]) == pytest.approx(r["q"][i, k], abs=1e-6)
            assert float(rows[i][f"{a}_mm_per_s"]) == pytest.approx(r["qd"][i, k], abs=1e-6)
    # The samples are the inverse kinematics of the poses.
    assert np.allclose(m.ik(r["x"]).actuators, r["q"], atol=1e-9)
    # The summary alone: the same summary, no samples kept.
    s2 = m.motion(gcode=pathlib.Path(ARC), start=[32, -32, -290, 0, 0, 0], feed=10000 / 60,
                  points=101, samples=False)
    assert s2["summary"] == r["summary"] and len(s2["t"]) == 0 and s2["q"].shape == (0, 3)


def test_parquet_series_hold_the_python_results_at_full_precision(tmp_path):
    """`--format parquet` read by pyarrow (an independent reader): the CSV's columns and
    rows, each value Python's own result to the last bits where the CSV rounds to six
    decimals, nulls where the CSV has empty fields."""
    import pyarrow.parquet as pq  # the [sweep] extra, which scripts/test installs
    m = pkm.load(TRIPOD)
    r = m.motion(gcode=pathlib.Path(ARC), start=[32, -32, -290, 0, 0, 0], feed=10000 / 60,
                 points=101)
    args = ["motion", TRIPOD, "--gcode", ARC, "--from", "32,-32,-290", "--feed", "10000",
            "--points", "101"]
    cli(*args, "--out", str(tmp_path / "c"))
    cli(*args, "--format", "parquet", "--out", str(tmp_path / "p"))
    assert not (tmp_path / "p" / "actuators.csv").exists()
    f = pq.ParquetFile(tmp_path / "p" / "actuators.parquet")
    assert f.schema_arrow.metadata[b"pkm.machine"].decode() == m.name
    t = f.read().to_pydict()
    with open(tmp_path / "c" / "actuators.csv") as h:
        rows = list(csv.DictReader(h))
    assert list(t) == list(rows[0])
    assert len(t["t_s"]) == len(rows) == len(r["t"])
    for i, row in enumerate(rows):
        assert t["line"][i] == (int(row["line"]) if row["line"] else None)
        for k, v in row.items():
            if k != "line":
                assert abs(t[k][i] - float(v)) <= 5e-7, (i, k)
    assert np.array_equal(np.array(t["t_s"]), r["t"])
    for k, a in enumerate(r["columns"][1]):
        for col, arr in ((f"{a}_mm", r["q"]), (f"{a}_mm_per_s", r["qd"]),
                         (f"{a}_mm_per_s2", r["qdd"])):
            assert np.array_equal(np.array(t[col]), arr[:, k]), col

    w = m.workspace()
    cli("workspace", TRIPOD, "--format", "parquet", "--out", str(tmp_path / "w"))
    p = pq.read_table(tmp_path / "w" / "points.parquet").to_pydict()
    assert np.array_equal(np.array([p["X_mm"], p["Y_mm"], p["Z_mm"]]).T, w["points"])
    assert p["reachable"] == list(w["reachable"])
    cond = np.array([np.nan if c is None else c for c in p["condition"]])
    assert np.array_equal(cond, w["condition"], equal_nan=True)
    assert p["status"] == [w["status_names"][s] for s in w["status"]]
    assert p["binding"] == [w["binding_names"][b] if b >= 0 else None for b in w["binding"]]


def test_motion_along_a_path_of_waypoints():
    m = pkm.load(TRIPOD)
    a = m.home.copy()
    b = a.copy()
    b[0] += 20
    c = b.copy()
    c[1] += 20
    r = m.motion(path=np.array([a, b, c]), feed=50.0, profile="trapezoid", rate=500)
    assert set(r["line"]) == {1, 2}
    assert np.allclose(r["x"][0], a) and np.allclose(r["x"][-1], c)
    # Velocities are the time derivative of the positions (central differences).
    dt = np.diff(r["t"])
    mid = (r["q"][2:] - r["q"][:-2]) / (dt[1:] + dt[:-1])[:, None]
    err = np.abs(mid - r["qd"][1:-1])
    # Equal but at the profile's corners (acceleration steps) and the move boundary.
    assert (err < 1e-3).mean() > 0.97, np.sort(err.ravel())[-10:]


def test_a_robot_motion_keeps_turning_its_wrist():
    # The KR 30 turns the tool 300 deg about Z: A6 turns 300 deg the other way,
    # continuously (each sample continues the one before, not the solution nearest
    # home, which jumped 360 deg at C = 180), and its positions integrate its rates.
    m = pkm.load(example("kr30-dh.toml"))
    r = m.motion(gcode="G90 G21\nG1 C300 F3000\n", rate=1000)
    a6 = r["q"][:, 5]
    assert math.degrees(a6[-1]) == pytest.approx(-300.0, abs=1e-9)
    dt = np.diff(r["t"])
    step = np.diff(a6) - 0.5 * dt * (r["qd"][1:, 5] + r["qd"][:-1, 5])
    assert np.abs(step).max() < 1e-9
    assert r["summary"]["actuators"]["A6"]["travel"] == pytest.approx(300.0, rel=1e-9)


def test_a_robot_path_through_ik_keeps_turning_its_wrist(tmp_path):
    # Rows of a path: A6 = -C continues to -300 deg with continuous=True, as
    # `pkm ik --continuous` writes it; each row nearest home comes back within half
    # a turn of 0.
    m = pkm.load(example("kr30-dh.toml"))
    c = np.radians(np.arange(0.0, 301.0, 10.0))
    poses = np.column_stack(
        [np.full_like(c, 1170.0), 0 * c, np.full_like(c, 1540.0), np.full_like(c, -math.pi), 0 * c, c]
    )
    path = m.ik(poses, continuous=True)
    assert path.reachable.all()
    assert np.allclose(np.degrees(path.actuators[:, 5]), -np.degrees(c), atol=1e-9)
    each = m.ik(poses)
    assert np.abs(np.degrees(each.actuators[:, 5])).max() <= 180.0 + 1e-9
    csv_in = tmp_path / "path.csv"
    rows = "\n".join(
        f"1170,0,1540,-180,0,{math.degrees(v):.12g}" for v in c
    )
    csv_in.write_text("X,Y,Z,A,B,C\n" + rows + "\n")
    out = tmp_path / "joints.csv"
    cli("ik", example("kr30-dh.toml"), "--input", str(csv_in), "--output", str(out), "--continuous")
    with open(out) as f:
        a6 = [float(r["A6_deg"]) for r in csv.DictReader(f)]
    assert np.allclose(a6, np.degrees(path.actuators[:, 5]), atol=1e-6)


def test_errors_equal_the_command(tmp_path):
    m = pkm.load(HEX)
    e = m.errors()
    j = cli("errors", HEX, "--json", "--out", str(tmp_path))
    assert e["budget"]["worst_case"] == pytest.approx(j["budget_worst_case"], rel=1e-12)
    assert e["budget"]["rss"] == pytest.approx(j["budget_rss"], rel=1e-12)
    # One tolerance per kind: the worst case scales with the tolerances.
    e2 = m.errors(tolerances={"joint": 0.02, "length": 0.02, "zero": 0.02, "angle": 2e-5})
    assert e2["budget"]["worst_case"] == pytest.approx(2 * e["budget"]["worst_case"], rel=1e-9)
    # A deviation's exact error is about its first-order sensitivity.
    name = m.parameters[0]["name"]
    d = m.errors(deviations={name: 0.01})
    pos = np.array(d["pose_error"]["position"])
    sens = np.array(d["sensitivities"][0]["position"])
    assert np.allclose(pos, 0.01 * sens, atol=1e-6)
    mc = m.errors(monte_carlo=2000, seed=3)["monte_carlo"]
    assert mc["samples"] == 2000 and 0 < mc["max"] <= e["budget"]["worst_case"] * 1.0001


def test_simulated_campaign_is_identified():
    m = pkm.load(HEX)
    s = pkm.simulate_measurements(m, states=40, holdout=10, deviation=0.5, seed=4)
    assert s["true_poses"].shape == (50, 6)
    c = pkm.calibrate(m, s["measurements"], validation=s["validation"])
    truth = s["true_parameters"]
    nominal = pkm.simulate_measurements(m, states=1, deviation=0.0, point_noise=0.0,
                                        length_noise=0.0)["true_parameters"]
    before = np.sqrt(np.mean((nominal - truth) ** 2))
    after = np.sqrt(np.mean((np.array(c["values"]) - truth) ** 2))
    assert after < before / 5, (before, after)
    v = c["validation"]
    assert v["identified"]["rms"] < v["nominal"]["rms"] / 10
    ident = c["machine"]
    assert isinstance(ident, pkm.Machine) and "identified" in c["identified_toml"]
    # The identified machine is the identified file's, and differs from the nominal.
    x = s["true_poses"][0]
    again = pkm.Machine.from_toml(c["identified_toml"])
    assert np.array_equal(ident.ik(x)[0], again.ik(x)[0])
    assert not np.allclose(ident.ik(x)[0], m.ik(x)[0], atol=1e-3)
    assert pkm.Machine.from_toml(s["true_machine"]).kind == "hexapod"


def test_a_pentapod_is_identified_from_points_on_its_tool_axis():
    m = pkm.load(example("pentapod-linuxcnc.toml"))
    s = pkm.simulate_measurements(m, states=40, holdout=10, fixture_radius=150.0, seed=2)
    # The library's fixture for a pentapod: the tool tip and a point 150 mm up its axis.
    assert "# fixture P2 = 0, 0, 150" in s["measurements"]
    c = pkm.calibrate(m, s["measurements"], validation=s["validation"])
    names = c["identification"]["names"]
    assert len(names) == 30 and "tool.z" not in names
    v = c["validation"]
    assert v["identified"]["rms"] < v["nominal"]["rms"] / 10
    assert pkm.Machine.from_toml(c["identified_toml"]).kind == "pentapod"


def test_the_default_campaign_fits_a_micro_hexapod():
    # 15 mm: the machine-tool defaults (+-100 mm) find no poses; the defaults are
    # fitted to the machine (1/16, as pkm simulate-measurements').
    m = pkm.load(ROOT / "tests/fixtures/micro-hexapod.toml")
    s = pkm.simulate_measurements(m, states=30, holdout=10, seed=3)
    assert "# fixture P1 = 0, 12.5, 0" in s["measurements"]
    nominal = pkm.simulate_measurements(m, states=1, deviation=0.0)["true_parameters"]
    assert 0 < np.max(np.abs(s["true_parameters"] - nominal)) <= 0.0625
    assert np.max(np.abs(s["true_poses"][:, :3] - [0, 0, 30])) <= 6.25
    c = pkm.calibrate(m, s["measurements"], validation=s["validation"])
    v = c["validation"]
    assert v["identified"]["rms"] < v["nominal"]["rms"] / 5
    with pytest.raises(pkm.InvalidInputError, match="poses within the limits"):
        pkm.simulate_measurements(m, translation=100.0)



def test_random_states_keep_away_from_singularities():
    # A micro tripod at 1/8 of the default spans reaches the plane of its base joints:
    # unbounded, states far beyond its home's condition number are drawn; with the
    # bound (4 by default) none is, and a bound below 1 is refused.
    m = pkm.load(ROOT / "tests/fixtures/micro-tripod.toml")
    # No deviations: the true machine is the nominal one, whose conditions are asked.
    kw = dict(states=50, translation=12.5, deviation=0.0, fixture_radius=25.0, seed=1)
    home = m.condition(m.home)

    def worst(**more):
        poses = pkm.simulate_measurements(m, **kw, **more)["true_poses"]
        return max(m.condition(x) for x in poses) / home

    assert worst() <= 4
    assert worst(condition_ratio=float("inf")) > 20
    with pytest.raises(pkm.InvalidInputError, match="condition ratio"):
        pkm.simulate_measurements(m, condition_ratio=0.5)


def test_errors_are_raised_with_pkm_messages(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(open(HEX).read().replace("type = \"hexapod\"", "type = \"hexapod\"\nbogus = [1,"))
    with pytest.raises(pkm.MachineFileError) as e:
        pkm.load(bad)
    assert str(bad) in str(e.value) and e.value.line is not None
    with pytest.raises(pkm.MachineFileError):
        pkm.load(tmp_path / "missing.toml")
    m = pkm.load(HEX)
    with pytest.raises(pkm.InvalidInputError, match="shape"):
        m.ik(np.zeros((3, 5)))
    with pytest.raises(pkm.InvalidInputError, match="not a finite number"):
        m.ik([0, 0, float("nan"), 0, 0, 0])
    with pytest.raises(pkm.InvalidInputError):
        m.ik("not numbers")
    with pytest.raises(pkm.InvalidInputError, match="G-code"):
        pkm.load(TRIPOD.replace("tripod-seed000", "p3rp-seed004")).motion(gcode="G1 X1 F100")
    with pytest.raises(pkm.InvalidInputError, match="max.samples"):
        pkm.load(TRIPOD).motion(gcode=pathlib.Path(ARC), start=[32, -32, -290, 0, 0, 0], max_samples=10)
    with pytest.raises(pkm.InvalidInputError, match="deviations"):
        m.errors(deviations={"no such parameter": 1.0})
    with pytest.raises(pkm.InvalidInputError):
        m.errors(tolerances={"joint": 1e300})
    # A range per kind of quantity: 100 mm, 10 deg.
    with pytest.raises(pkm.InvalidInputError, match="is not a tolerance or deviation"):
        m.errors(deviations={m.parameters[0]["name"]: 1e5})
    with pytest.raises(pkm.InvalidInputError, match="from 0 to 100 mm"):
        m.errors(tolerances={"length": 150.0})
    with pytest.raises(pkm.UnsupportedError) as u:
        pkm.simulate_measurements(pkm.load(example("mc300.toml")))
    assert u.value.analysis == "identification"
    assert issubclass(pkm.UnsupportedError, pkm.Error) and issubclass(pkm.Error, Exception)
    with pytest.raises(pkm.MachineFileError) as e:
        pkm.Machine.from_dict({"type": "hexapod", "name": 3})
    assert e.value.field


def test_the_tour_runs(capsys):
    import runpy

    runpy.run_path(str(ROOT / "examples" / "python" / "tour.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "reachable" in out and "identified" in out


def test_garbage_input_raises_never_crashes():
    """Random shapes, dtypes and values into every call: a pkm.Error (or TypeError
    for a wrong Python type), never a crash, a hang or another exception."""
    rng = np.random.default_rng(11)
    m = pkm.load(HEX)
    values = [
        np.zeros((0, 6)), np.zeros((2, 7)), np.zeros((3, 6, 1)), np.full(6, np.inf),
        np.full((4, 6), np.nan), np.full(6, 1e300), np.array(["a"] * 6), [None] * 6,
        "text", {"a": 1}, 3.0, np.zeros(6, dtype=np.int64), np.zeros(6, dtype=np.float32),
        rng.normal(0, 1e6, (5, 6)), np.asfortranarray(rng.normal(0, 1, (5, 6))),
        rng.normal(0, 1, (10, 6))[::2], [[1, 2, 3]], [],
    ]
    calls = [
        lambda v: m.ik(v), lambda v: m.ik(v, check=False), lambda v: m.fk(v),
        lambda v: m.fk(m.ik(m.home)[0], start=v), lambda v: m.jacobian(v),
        lambda v: m.condition(v), lambda v: m.tool_pose(v), lambda v: m.check_limits(v),
        lambda v: m.workspace(bounds=v), lambda v: m.workspace(orientation=v),
        lambda v: m.motion(path=v, feed=10.0), lambda v: m.motion(gcode=v),
        lambda v: m.errors(v), lambda v: m.errors(tolerances=v),
        lambda v: pkm.Machine.from_dict(v) if isinstance(v, dict) else pkm.Machine.from_toml(str(v)),
        lambda v: pkm.calibrate(m, v),
    ]
    for call in calls:
        for v in values:
            try:
                call(v)
            except (pkm.Error, TypeError):
                pass
    # Absurd sizes are refused before any work.
    with pytest.raises(pkm.InvalidInputError):
        m.workspace(bounds=[[-1e6, 1e6]] * 3, step=1e-3)
    with pytest.raises(pkm.InvalidInputError):
        m.motion(gcode="G1 X10 F0.000001\n", max_samples=1000)


HEXAPOD = example("hexapod-linuxcnc.toml")


def test_statics_equals_the_command():
    m = pkm.load(HEXAPOD)
    pose = [50.0, 0.0, 550.0, 0.0, math.radians(5.0), 0.0]
    # N and N mm here; the command takes the moment in N m.
    r = m.statics(pose, wrench=[200.0, 0.0, -1000.0, 0.0, 0.0, 10000.0])
    s = cli(
        "statics", HEXAPOD, "--pose=50,0,550,0,5,0", "--wrench=200,0,-1000,0,0,10", "--json"
    )
    assert isinstance(r["actuator_forces"], np.ndarray)
    assert r["actuator_forces"] == pytest.approx(list(s["actuator_forces"].values()), rel=1e-9)
    k = r["stiffness"]
    assert np.array(k["matrix"]) == pytest.approx(np.array(s["stiffness"]), rel=1e-9)
    assert k["deflection"] == pytest.approx(s["deflection"], rel=1e-9, abs=1e-15)
    assert r["stiffness_error"] is None


def test_a_stiffness_map_equals_statics_pose_by_pose():
    m = pkm.load(HEXAPOD)
    rng = np.random.default_rng(3)
    poses = np.tile(m.home, (50, 1))
    poses[:, :3] += rng.uniform(-50, 50, (50, 3))
    poses[:, 3:] += rng.uniform(-0.1, 0.1, (50, 3))
    s = m.stiffness(poses, matrices=True)
    assert s["smallest_n_per_um"].shape == (50,) and s["matrices"].shape == (50, 6, 6)
    assert s["failed"] == 0 and np.isfinite(s["smallest_n_per_um"]).all()
    for i in (0, 13, 49):
        one = m.statics(poses[i])["stiffness"]
        assert s["smallest_n_per_um"][i] == pytest.approx(one["smallest_translational_n_per_um"], rel=1e-12)
        assert s["matrices"][i] == pytest.approx(np.array(one["matrix"]), rel=1e-12)
    w = s["weakest"]
    assert s["smallest_n_per_um"][w] == np.nanmin(s["smallest_n_per_um"])


def test_statics_refuses_a_bad_wrench_and_names_missing_stiffness():
    with pytest.raises(pkm.InvalidInputError, match="wrench"):
        pkm.load(HEXAPOD).statics(wrench=[1.0, 2.0])
    r = pkm.load(TRIPOD).statics(wrench=[0.0, 0.0, -100.0])
    assert r["stiffness"] is None and "no `stiffness` for drives" in r["stiffness_error"]
