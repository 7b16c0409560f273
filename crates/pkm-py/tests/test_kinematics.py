"""Kinematics on numpy arrays: equal to the pkm command, batches equal single calls,
forward and inverse round trips, the Jacobian against finite differences."""

import math
import pathlib

import numpy as np
import pytest

import pkm
from conftest import all_examples, cli, example

HEX = example("hexapod-linuxcnc.toml")


def user(m, x, kind):
    """Internal (mm, rad) to the command line's units (mm, deg)."""
    units = [c["unit"] for c in (m.coordinates if kind == "pose" else m.actuators)]
    return [math.degrees(v) if u == "rad" else v for v, u in zip(x, units)]


def random_poses(m, n, seed, spread=0.05):
    """Poses about home: driven coordinates spread by `spread` of the machine's size
    (lengths) or `spread` rad, held coordinates at home."""
    rng = np.random.default_rng(seed)
    home = m.home
    scale = max(m.characteristic_length, 1.0)
    x = np.tile(home, (n, 1))
    for k in m.driven:
        s = scale * spread if m.coordinates[k]["unit"] == "mm" else spread
        x[:, k] += rng.uniform(-s, s, n)
    return x


@pytest.mark.parametrize("path", all_examples())
def test_ik_equals_the_command_on_every_example(path):
    m = pkm.load(path)
    for x in random_poses(m, 3, 1, spread=0.02):
        q, reachable, message = m.ik(x)
        pose = ",".join(f"{v:.17g}" for v in user(m, x, "pose"))
        j = cli("ik", path, f"--pose={pose}", "--json")
        expected = [j["actuators"][a["name"]] for a in m.actuators]
        assert np.allclose(user(m, q, "act"), expected, rtol=1e-9, atol=1e-9)
        assert reachable == j["reachable"]
        if not reachable:
            first = j["violations"][0]
            assert message.startswith(first["limit"])


@pytest.mark.parametrize("path", all_examples())
def test_batch_ik_equals_single_calls(path):
    m = pkm.load(path)
    x = random_poses(m, 500, 2, spread=0.2)
    b = m.ik(x)
    q, reachable, limit = b
    assert q.shape == (500, len(m.actuators)) and reachable.dtype == bool
    assert len(b) == 500
    messages = b.messages()
    for i in range(0, 500, 7):
        try:
            qi, ok, msg = m.ik(x[i])
        except pkm.Error as e:
            assert np.isnan(q[i]).all() and not reachable[i]
            assert messages[i] == str(e)
            continue
        assert np.allclose(qi, q[i], rtol=1e-12, atol=1e-12)
        assert ok == reachable[i]
        assert msg == messages[i]
        if ok:
            assert limit[i] == -1
        else:
            assert msg.startswith(b.limit_names[limit[i]])
            assert b.excess[i] > 0


def test_batch_ik_names_the_limit_and_its_excess():
    m = pkm.load(HEX)
    x = np.tile(m.home, (3, 1))
    x[1, 2] += 1000.0  # far above: struts too long
    b = m.ik(x)
    assert list(b.reachable) == [True, False, True]
    name = b.limit_names[b.limit[1]]
    assert "length" in name and b.limit_units[b.limit[1]] == "mm"
    q = b.actuators[1]
    (k,) = [k for k, a in enumerate(m.actuators) if f"strut {a['name']} length" == name]
    assert b.excess[1] == pytest.approx(q[k] - m.actuators[k]["max"], rel=1e-12)
    assert b.messages()[1].startswith(f"{name} {q[k]:.3f} mm is above its maximum")


@pytest.mark.parametrize("path", all_examples())
def test_fk_inverts_ik(path):
    m = pkm.load(path)
    x = random_poses(m, 200, 3, spread=0.01)
    q, reachable, _ = m.ik(x)
    ok = ~np.isnan(q).any(axis=1)
    f = m.fk(q[ok])
    assert f.solved.all(), f.messages()[:3]
    # Every solved pose reproduces its actuators (the forward solution may be another
    # assembly mode only where the machine has several; near home it is this one).
    back, _, _ = m.ik(f.poses)
    assert np.allclose(back, q[ok], atol=1e-9)
    d = f.poses - x[ok]
    for k, c in enumerate(m.coordinates):
        if c["unit"] == "rad":  # the same angle, maybe on the other side of +-pi
            d[:, k] = (d[:, k] + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(d).max() < 1e-6
    pose, info = m.fk(q[ok][0])
    assert np.allclose(pose, f.poses[0], atol=1e-12)
    assert info["residual"] < 1e-9 and info["iterations"] == f.iterations[0]


@pytest.mark.parametrize("path", all_examples())
def test_jacobian_equals_finite_differences_of_ik(path):
    m = pkm.load(path)
    x = random_poses(m, 1, 4, spread=0.01)[0]
    j = m.jacobian(x)
    assert j.shape == (len(m.actuators), len(m.coordinates))
    for k in m.driven:
        h = 1e-6 if m.coordinates[k]["unit"] == "mm" else 1e-7
        xp, xm = x.copy(), x.copy()
        xp[k] += h
        xm[k] -= h
        fd = (m.ik(xp)[0] - m.ik(xm)[0]) / (2 * h)
        assert np.allclose(j[:, k], fd, rtol=1e-5, atol=1e-6), (k, j[:, k], fd)


def test_condition_of_one_pose_and_of_many():
    m = pkm.load(HEX)
    x = random_poses(m, 50, 5)
    c = m.condition(x)
    assert c.shape == (50,) and (c >= 1).all()
    assert m.condition(x[7]) == c[7]
    t = m.tool_pose(m.home)
    assert t.shape == (4, 4) and np.allclose(t[3], [0, 0, 0, 1])
    assert np.allclose(t[:3, 3], m.home[:3])


def test_tool_poses_of_many_poses():
    """(N, P) poses give (N, 4, 4) tool poses, row by row the single call's; a robot
    in joint coordinates gives the tool poses of the same robot in tool coordinates
    (its own forward kinematics, another class); a TCP machine's tool tip is its X,
    Y, Z."""
    text = pathlib.Path(example("kr30-dh.toml")).read_text()
    joints = pkm.Machine.from_toml('pose = "joints"\n' + text)
    assert joints.pose_space != "spatial"
    rng = np.random.default_rng(40)
    q = rng.uniform(-2.0, 2.0, (50, 6))
    t = joints.tool_pose(q)
    assert t.shape == (50, 4, 4)
    assert np.array_equal(t[7], joints.tool_pose(q[7]))
    assert np.array_equal(t[:, 3], np.tile([0.0, 0.0, 0.0, 1.0], (50, 1)))
    robot = pkm.load(example("kr30-dh.toml"))
    for k in range(0, 50, 7):
        pose, _ = robot.fk(q[k])
        assert np.allclose(robot.tool_pose(pose), t[k], rtol=0, atol=1e-9), k
    mc = pkm.load(example("mc300.toml"))
    x = np.tile(mc.home, (3, 1))
    x[1, :3] = [250.0, -120.0, 300.0]
    t = mc.tool_pose(x)
    assert np.allclose(t[1, :3, 3], [250.0, -120.0, 300.0], rtol=0, atol=1e-9)
    assert np.array_equal(t[2], mc.tool_pose(mc.home))


def test_metadata():
    m = pkm.load(HEX)
    assert m.kind == "hexapod" and m.pose_space == "spatial"
    assert [c["name"] for c in m.coordinates] == ["X", "Y", "Z", "A", "B", "C"]
    assert [c["unit"] for c in m.coordinates] == ["mm"] * 3 + ["rad"] * 3
    assert len(m.actuators) == 6 and m.actuators[0]["min"] < m.actuators[0]["max"]
    assert m.capabilities["identification"] is True
    assert "hexapod" in repr(m)
    assert any(t == "pentapod" for t, _ in pkm.machine_types())
    names = [p["name"] for p in m.parameters]
    assert len(names) == len(set(names)) and any(n.endswith(".x") for n in names)


def test_from_dict_and_from_toml_give_the_same_machine():
    import tomllib

    with open(HEX, "rb") as f:
        d = tomllib.load(f)
    a = pkm.Machine.from_dict(d)
    b = pkm.Machine.from_toml(open(HEX).read())
    x = random_poses(a, 100, 6)
    assert np.array_equal(a.ik(x).actuators, pkm.load(HEX).ik(x).actuators)
    assert np.array_equal(b.ik(x).actuators, a.ik(x).actuators)
    # numpy arrays and scalars in the dict are taken as numbers: the same machine.
    d2 = dict(d)
    d2["base_joints"] = {k: np.asarray(v) for k, v in d["base_joints"].items()}
    d2["platform_joints"] = {k: tuple(np.float64(c) for c in v)
                             for k, v in d["platform_joints"].items()}
    d2["struts"] = [{**s, "length": np.asarray(s["length"]), "max_velocity": np.float64(s["max_velocity"])}
                    for s in d["struts"]]
    assert isinstance(d2["base_joints"]["B1"], np.ndarray)
    c = pkm.Machine.from_dict(d2)
    assert np.array_equal(c.ik(x).actuators, a.ik(x).actuators)
    assert c.actuators == a.actuators


def test_batches_release_the_gil_and_agree_across_threads():
    import concurrent.futures
    import threading

    m = pkm.load(HEX)
    x = random_poses(m, 20000, 7)
    ref = m.ik(x).actuators
    with concurrent.futures.ThreadPoolExecutor(4) as ex:
        outs = list(ex.map(lambda s: m.ik(x[s::4]).actuators, range(4)))
    for s, o in enumerate(outs):
        assert np.array_equal(o, ref[s::4])
    # While a long batch (about 0.1 s) runs in another thread, this thread keeps
    # running Python: its longest pause is a fraction of the batch (converting the
    # arrays holds the GIL). With the GIL held throughout, it would pause for all of
    # it.
    import time

    big = random_poses(m, 1_000_000, 8)
    took = []

    def batch():
        t0 = time.perf_counter()
        m.ik(big)
        took.append(time.perf_counter() - t0)

    t = threading.Thread(target=batch)
    last = time.perf_counter()
    longest = 0.0
    t.start()
    while t.is_alive():
        now = time.perf_counter()
        longest = max(longest, now - last)
        last = now
    t.join()
    assert longest < 0.5 * took[0], (longest, took[0])


def test_ik_without_the_limit_check():
    m = pkm.load(HEX)
    x = random_poses(m, 2000, 8, spread=0.3)
    full = m.ik(x)
    raw = m.ik(x, check=False)
    assert np.array_equal(raw.actuators, full.actuators, equal_nan=True)
    solved = ~np.isnan(full.actuators).any(axis=1)
    assert np.array_equal(raw.reachable, solved)
    assert (full.reachable <= raw.reachable).all() and full.reachable.sum() < raw.reachable.sum()
    q, ok, msg = m.ik(x[0], check=False)
    assert np.array_equal(q, full.actuators[0]) and ok and msg is None


def test_values_beyond_sane_magnitudes_are_refused_with_their_place():
    m = pkm.load(HEX)
    x = np.tile(m.home, (3, 1))
    x[2, 3] = 1e300
    with pytest.raises(pkm.InvalidInputError, match="row 2, column 3: 1e300 is beyond"):
        m.ik(x)
    with pytest.raises(pkm.InvalidInputError, match="poses"):
        m.ik([1e300, 0, 500, 0, 0, 0])
    with pytest.raises(pkm.InvalidInputError, match="bounds"):
        m.workspace(bounds=[[-1e300, 0], [0, 1], [0, 1]])
    assert pkm.InvalidInputError.__module__ == "pkm"


def test_machines_pickle_from_their_text():
    import pickle

    m = pkm.load(HEX)
    back = pickle.loads(pickle.dumps(m))
    x = random_poses(m, 100, 9)
    assert np.array_equal(back.ik(x).actuators, m.ik(x).actuators)
    assert back.name == m.name and back.toml == m.toml
    with pytest.raises(TypeError, match="URDF"):
        pickle.dumps(pkm.load(str(HEX).replace("machines/hexapod-linuxcnc.toml", "robots/ur5-like.urdf")))


def test_batches_read_any_layout_and_name_the_first_bad_value():
    """A C-contiguous float64 array is read in place (checked by blocks on all cores);
    other layouts are copied: both give the same rows, and a bad value far into a
    large array is named by its own row and column, the first one when there are two."""
    m = pkm.load(HEX)
    x = random_poses(m, 100_000, 12, spread=0.1)
    c = m.ik(x)
    for other in (np.asfortranarray(x), np.repeat(x, 2, axis=0)[::2]):
        assert np.array_equal(other, x)
        o = m.ik(other)
        assert np.array_equal(o.actuators, c.actuators, equal_nan=True)
        assert np.array_equal(o.reachable, c.reachable)
    bad = x.copy()
    bad[70_001, 4] = np.nan
    bad[99_000, 0] = np.inf
    with pytest.raises(pkm.InvalidInputError, match="row 70001, column 4: NaN is not a finite number"):
        m.ik(bad)
    with pytest.raises(pkm.InvalidInputError, match="row 70001, column 4"):
        m.ik(np.asfortranarray(bad))
