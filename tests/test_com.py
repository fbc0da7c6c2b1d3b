"""Centre of mass, its Jacobian and the centroidal momentum against Pinocchio
(`centerOfMass`, `jacobianCenterOfMass`, `computeCentroidalMap`,
`computeCentroidalMomentumTimeVariation`) on example-robot-data URDFs, fixed and free base,
to 1e-10 relative; the COM against the mass-weighted link COMs; the momentum rate against
central differences."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err
from test_frames import pin_q, random_q, robot  # noqa: F401  (robot: the fixture)

pin = pytest.importorskip("pinocchio")

TOL = 1e-10
SWAP = [3, 4, 5, 0, 1, 2]


def test_com_and_jacobian_match_pinocchio(robot):  # noqa: F811
    name, model, pm = robot
    data = pm.createData()
    rng = np.random.default_rng(21)
    qs = np.array([random_q(model, rng) for _ in range(3)])
    coms, jacs = model.center_of_mass(qs, jacobian=True)
    for k, q in enumerate(qs):
        v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
        qp = pin_q(pm, model, q)
        pin.centerOfMass(pm, data, qp, v, a)
        c, vc, ac = model.center_of_mass_motion(q, v, a)
        assert record(f"com {name}", rel_err(c, data.com[0])) < TOL
        np.testing.assert_array_equal(coms[k], model.center_of_mass(q))
        assert rel_err(vc, data.vcom[0]) < TOL and rel_err(ac, data.acom[0]) < TOL
        jc = pin.jacobianCenterOfMass(pm, data, qp)
        assert record(f"com jacobian {name}", rel_err(jacs[k], jc)) < TOL


def test_centroidal_map_and_bias_match_pinocchio(robot):  # noqa: F811
    name, model, pm = robot
    data = pm.createData()
    rng = np.random.default_rng(22)
    q = random_q(model, rng)
    v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
    qp = pin_q(pm, model, q)
    ag = pin.computeCentroidalMap(pm, data, qp)
    out = model.centroidal(q, v, a)
    assert record(f"centroidal map {name}", rel_err(out["A"], ag[SWAP])) < TOL
    dh = pin.computeCentroidalMomentumTimeVariation(pm, data, qp, v, a)
    assert rel_err(out["momentum"], data.hg.vector[SWAP]) < TOL
    assert record(f"centroidal rate {name}", rel_err(out["rate"], dh.vector[SWAP])) < TOL
    # The bias Ȧ_g v: the rate at zero acceleration.
    dh0 = pin.computeCentroidalMomentumTimeVariation(pm, data, qp, v, np.zeros(model.nv))
    assert rel_err(model.centroidal(q, v)["rate"], dh0.vector[SWAP]) < TOL


def test_com_is_the_mass_weighted_link_coms():
    m = pmd.Model()
    rng = np.random.default_rng(0)
    masses, coms = [], []
    parent = -1
    for k in range(4):
        mass, com = 1.0 + k, rng.normal(size=3) * 0.1
        masses.append(mass)
        coms.append(com)
        parent = m.add_body(pmd.RigidBody(mass, com, np.eye(3) * 0.01), pmd.Revolute(rng.normal(size=3)),
                            parent=parent, translation=rng.normal(size=3) * 0.3)
    q = rng.normal(size=4)
    rot, org = m.placements(q)
    want = sum(mk * (o + r @ c) for mk, o, r, c in zip(masses, org, rot, coms)) / sum(masses)
    np.testing.assert_allclose(m.center_of_mass(q), want, rtol=0, atol=1e-14)


def test_momentum_rate_is_the_derivative_of_the_momentum():
    from conftest import robots_dir
    from test_frames import FIXED, load

    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    model, pm = load(str(root / FIXED["panda"]), False)
    rng = np.random.default_rng(4)
    q = random_q(model, rng)
    v = rng.normal(size=model.nv)
    h = 1e-5
    hp = model.centroidal(q + h * v, v)["momentum"]
    hm = model.centroidal(q - h * v, v)["momentum"]
    assert rel_err(model.centroidal(q, v)["rate"], (hp - hm) / (2 * h)) < 1e-7


def test_com_of_a_massless_model_says_so():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, (0, 0, 0), np.eye(3)), pmd.Fixed())
    with pytest.raises(pmd.errors.InvalidInputError, match="no moving body has mass"):
        m.center_of_mass(np.zeros(0))
