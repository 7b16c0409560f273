"""Inverse dynamics of serial robots against Pinocchio's RNEA (the `pin` wheel), on two
URDF robots with inertias: 1000 random (q, qd, qdd) each, to 1e-9 relative."""

import numpy as np
import pytest

import pkm
from conftest import ROOT

pin = pytest.importorskip("pinocchio")

ROBOTS = [
    ROOT / "examples" / "robots" / "ur5-like.urdf",
    ROOT / "tests" / "fixtures" / "urdf" / "scara-tool.urdf",
]


@pytest.mark.parametrize("urdf", ROBOTS, ids=lambda p: p.stem)
def test_rnea_equals_pinocchio(urdf):
    m = pkm.load(str(urdf))
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    n = model.nv
    assert n == len(m.actuators) == model.nq
    # pkm's standard gravity (9.80665 m/s^2) in Pinocchio too.
    model.gravity.linear = np.array([0.0, 0.0, -9.80665])
    rng = np.random.default_rng(1)
    lo = np.maximum(model.lowerPositionLimit, -3.0)
    hi = np.minimum(model.upperPositionLimit, 3.0)
    q = rng.uniform(lo, hi, (1000, n))
    qd = rng.uniform(-2.0, 2.0, (1000, n))
    qdd = rng.uniform(-10.0, 10.0, (1000, n))
    # pkm's units: mm for a slide, N mm for a revolute joint's torque.
    slide = np.array([a["unit"] == "mm" for a in m.actuators])
    to_pkm = np.where(slide, 1000.0, 1.0)
    torque_si = np.where(slide, 1.0, 1e-3)
    ours = m.inverse_dynamics(q * to_pkm, qd * to_pkm, qdd * to_pkm) * torque_si
    worst = 0.0
    for k in range(1000):
        theirs = pin.rnea(model, data, q[k], qd[k], qdd[k])
        scale = max(np.abs(theirs).max(), 1.0)
        worst = max(worst, np.abs(ours[k] - theirs).max() / scale)
    assert worst < 1e-9, worst


def test_gravity_and_a_tool_load_reach_the_joints_as_pinocchio_has_them():
    urdf = ROBOTS[0]
    m = pkm.load(str(urdf))
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    q = np.array([0.3, -1.1, 0.7, -0.4, 1.2, 0.5])
    zero = np.zeros(6)
    # A 20 N push along X and 2 N m about Z on the tool, base frame.
    w = np.array([20.0, 0.0, 0.0, 0.0, 0.0, 2.0])
    ours = m.inverse_dynamics(q, zero, zero, gravity=[0.0, 0.0, -9810.0],
                              wrench=[*w[:3], *(w[3:] * 1e3)]) * 1e-3
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    tool = model.getFrameId("tool0")
    # The load on the tool at its origin, in the world frame: the joints hold it with
    # tau = g(q) - J^T w (J: the tool's world-aligned Jacobian).
    jac = pin.computeFrameJacobian(model, data, q, tool, pin.LOCAL_WORLD_ALIGNED)
    theirs = pin.rnea(model, data, q, zero, zero) - jac.T @ w
    assert np.abs(ours - theirs).max() < 1e-9 * np.abs(theirs).max()


def test_a_machine_without_masses_or_serial_chain_is_refused():
    with pytest.raises(pkm.InvalidInputError, match="mass properties"):
        pkm.load(str(ROOT / "examples" / "machines" / "kr30-dh.toml")).inverse_dynamics(
            np.zeros(6), np.zeros(6), np.zeros(6))
    with pytest.raises(pkm.Error, match="only serial machines"):
        pkm.load(str(ROOT / "examples" / "machines" / "hexapod-linuxcnc.toml")).inverse_dynamics(
            np.zeros(6), np.zeros(6), np.zeros(6))
