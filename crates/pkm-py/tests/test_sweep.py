"""Design sweeps: parameter spaces, objectives against direct calls, the Pareto front
against brute force, and a 2-worker Dask LocalCluster giving the serial table."""

import importlib.util
import math

import numpy as np
import pandas as pd
import pytest

import pkm
from conftest import ROOT
from pkm import sweep


def example_module():
    path = ROOT / "examples" / "python" / "sweep_hexapod.py"
    spec = importlib.util.spec_from_file_location("sweep_hexapod", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


EX = example_module()


def test_a_missing_sweep_dependency_names_the_extra(monkeypatch):
    # None in sys.modules makes the import fail as if scipy were not installed.
    monkeypatch.setitem(__import__("sys").modules, "scipy", None)
    monkeypatch.setitem(__import__("sys").modules, "scipy.stats", None)
    monkeypatch.setitem(__import__("sys").modules, "scipy.stats.qmc", None)
    with pytest.raises(ImportError, match=r"needs scipy for Latin hypercube sampling.*pkm\[sweep\]"):
        sweep.latin_hypercube({"a": (0, 1)}, 4)


def test_spaces():
    g = sweep.grid({"a": [1, 2, 3], "b": [10, 20]})
    assert list(g.columns) == ["a", "b"] and len(g) == 6
    assert g.iloc[1].tolist() == [1, 20]
    lhs = sweep.latin_hypercube({"a": (0, 1), "b": (5, 7)}, 50, seed=2)
    assert len(lhs) == 50 and lhs["b"].between(5, 7).all()
    # Latin: one sample in each of the 50 strata of every parameter.
    assert sorted(np.floor(lhs["a"] * 50).astype(int)) == list(range(50))
    s = sweep.sobol({"a": (0, 1)}, 64, seed=2)
    assert len(s) == 64 and s["a"].between(0, 1).all()
    with pytest.raises(pkm.InvalidInputError):
        sweep.latin_hypercube({"a": (1, 0)}, 4)


def test_objectives_equal_direct_calls():
    obj = EX.objectives(quick=True)
    p = EX.sweep.latin_hypercube(EX.SPACE, 1, seed=5).iloc[0].to_dict()
    m = pkm.Machine.from_dict(EX.hexapod(p))
    r = sweep.evaluate(m, obj)
    region = obj.region(m)
    b = m.ik(region)
    assert r["reachable_fraction"] == b.reachable.mean()
    assert r["reachable_volume_mm3"] == pytest.approx(b.reachable.mean() * 400 * 400 * 200)
    assert r["worst_condition"] == m.condition(region[b.reachable]).max()
    run = m.motion(gcode=EX.PROGRAM, rate=obj.rate)
    assert r["peak_actuator_speed"] == pytest.approx(
        max(s["peak_velocity"] for s in run["summary"]["actuators"].values()), rel=1e-12)
    worst = 0.0
    for corner in [(0, 0, 650)] + [(sx * 200, sy * 200, z) for sx in (-1, 1) for sy in (-1, 1)
                                   for z in (550, 750)]:
        p = region[0].copy()
        p[:3] = corner
        worst = max(worst, m.errors(p, tolerances=obj.tolerances)["budget"]["worst_case"])
    assert r["accuracy_worst_mm"] == worst


def test_the_stiffness_objective_equals_the_map():
    m = pkm.load(str(ROOT / "examples" / "machines" / "hexapod-linuxcnc.toml"))
    obj = sweep.Objectives(box=((-100, 100), (-100, 100), (500, 600)), step=50.0, stiffness=True)
    r = sweep.evaluate(m, obj)
    region = obj.region(m)
    ok = m.ik(region).reachable
    k = m.stiffness(region[ok])["smallest_n_per_um"]
    assert r["min_stiffness_n_per_um"] == np.nanmin(k) and 50 < np.nanmin(k) < 500
    assert "min_stiffness_n_per_um" in obj.columns()
    with pytest.raises(pkm.InvalidInputError, match="needs a required region"):
        sweep.evaluate(m, sweep.Objectives(stiffness=True))


def test_regions_reach_their_faces():
    m = pkm.load(str(ROOT / "examples" / "machines" / "hexapod-linuxcnc.toml"))
    # A step that does not divide the box: both faces still sampled, no gap wider
    # than the step.
    box = sweep.Objectives(box=((-200, 200), (-100, 100), (500, 560)), step=30.0).region(m)
    assert box[:, :3].min(axis=0).tolist() == [-200, -100, 500]
    assert box[:, :3].max(axis=0).tolist() == [200, 100, 560]
    xs = np.unique(box[:, 0])
    assert len(xs) == 15 and np.diff(xs).max() <= 30.0
    assert np.allclose(box[:, 3:], m.home[3:])
    obj = sweep.Objectives(cylinder=(0.0, 0.0, 100.0, 600.0, 700.0), step=20.0)
    x = obj.region(m)
    r = np.hypot(x[:, 0], x[:, 1])
    assert (r <= 100 + 1e-9).all() and r.max() == pytest.approx(100)
    assert x[:, 2].min() == 600 and x[:, 2].max() == 700
    assert obj.volume() == pytest.approx(math.pi * 100 ** 2 * 100)


def test_pareto_front_equals_brute_force():
    rng = np.random.default_rng(3)
    t = pd.DataFrame({"a": rng.random(200), "b": rng.random(200), "c": rng.random(200)})
    t.loc[5, "a"] = np.nan
    f = sweep.pareto_front(t, {"a": "min", "b": "max", "c": "min"})
    v = np.column_stack([t["a"], -t["b"], t["c"]])
    for i in range(200):
        if not np.isfinite(v[i]).all():
            assert not f[i]
            continue
        ok = np.isfinite(v).all(axis=1)
        dom = ((v[ok] <= v[i]).all(axis=1) & (v[ok] < v[i]).any(axis=1)).any()
        assert f[i] == (not dom)
    assert f.sum() > 0


def test_refused_candidates_are_rows_with_the_message(tmp_path):
    def build(p):
        d = EX.hexapod(p)
        if p["stroke"] > 400:
            d["struts"][0]["length"] = [900.0, 100.0]  # min above max: pkm refuses
        return d

    space = pd.DataFrame([{**dict.fromkeys(EX.SPACE, 0.0), "base_radius": 500,
                           "platform_radius": 200, "base_gap": 20, "platform_gap": 20,
                           "stroke": s} for s in (300.0, 450.0)])
    t = sweep.run(build, space, EX.objectives(quick=True))
    assert t["error"].isna().tolist() == [True, False]
    assert "MachineFileError" in t["error"][1] and "length" in t["error"][1]
    assert np.isnan(t.loc[1, "reachable_fraction"]) and t.loc[0, "reachable_fraction"] > 0
    sweep.write_parquet(t, tmp_path / "t.parquet")
    back = pd.read_parquet(tmp_path / "t.parquet")
    pd.testing.assert_frame_equal(back, t)
    assert [p.name for p in tmp_path.iterdir()] == ["t.parquet"]
    sweep.plot_pareto(t, "worst_condition", "reachable_volume_mm3",
                      sweep.pareto_front(t, {"worst_condition": "min"}), tmp_path / "p.svg")
    assert (tmp_path / "p.svg").read_text().lstrip().startswith("<?xml")


def test_local_cluster_gives_the_serial_table():
    space = sweep.latin_hypercube(EX.SPACE, 10, seed=7)
    obj = EX.objectives(quick=True)
    serial = sweep.run(EX.hexapod, space, obj)
    import os

    before = os.environ.get("RAYON_NUM_THREADS")
    client = sweep.local_cluster(2)
    assert os.environ.get("RAYON_NUM_THREADS") == before  # the workers' alone
    try:
        assert set(client.run(lambda: os.environ["RAYON_NUM_THREADS"]).values()) == {"1"}
        assert len(client.scheduler_info()["workers"]) == 2
        seen = []
        dist = sweep.run(EX.hexapod, space, obj, client=client, batch_size=3,
                         progress=lambda d, n: seen.append(d))
    finally:
        client.close()
    assert seen[-1] == 10 and len(seen) == 4
    pd.testing.assert_frame_equal(serial.drop(columns="seconds"), dist.drop(columns="seconds"))


def test_example_script_runs_quick(tmp_path, capsys):
    EX.main(["--workers", "0", "--quick", "--out", str(tmp_path)])
    t = pd.read_parquet(tmp_path / "sweep.parquet")
    assert len(t) == 16 and t["pareto"].any()
    assert "on the Pareto front" in capsys.readouterr().out
