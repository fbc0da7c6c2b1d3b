"""Inertial parameter identification (docs/identification.md): the torque regressor and
base parameters against Pinocchio's ``computeJointTorqueRegressor``, exact recovery on
noise-free data, physical consistency of the cells' estimate on noisy Panda data (and the
non-physical bodies plain least squares gives there), friction and armature recovered on a
chain with known values, and bad input."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G, build_model, build_pinocchio, random_state, random_tree, record, rel_err
from pointmass_dyn import identification as ident

pin = pytest.importorskip("pinocchio")


def pin_regressor(pm, qs, vs, acs):
    d = pm.createData()
    return np.vstack([pin.computeJointTorqueRegressor(pm, d, q, v, a).copy() for q, v, a in zip(qs, vs, acs)])


def pin_parameters(pm):
    return np.concatenate([pm.inertias[j].toDynamicParameters() for j in range(1, pm.njoints)])


def panda_states(pm, n, seed):
    rng = np.random.default_rng(seed)
    qs = np.array([pin.randomConfiguration(pm) for _ in range(n)])
    return qs, rng.normal(size=(n, pm.nv)), rng.normal(size=(n, pm.nv))


def test_regressor_and_parameters_equal_pinocchios_on_panda():
    pm = pin.buildModelFromUrdf(str(pmd.robots.urdf_path("panda")))
    pm.gravity.linear = G
    model = pmd.example_robot("panda")
    qs, vs, acs = panda_states(pm, 20, 1)
    ours = ident.torque_regressor(model, qs, vs, acs, gravity=G)
    theirs = pin_regressor(pm, qs, vs, acs)
    e = record("identification: panda regressor vs Pinocchio", rel_err(ours.data, theirs))
    assert e <= 1e-12
    assert rel_err(ours.values, pin_parameters(pm)) <= 1e-12
    assert ours.names[:10] == [f"panda_link1.{p}" for p in ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")]
    # Y π is the inverse dynamics.
    tau = np.array([model.inverse_dynamics(q, v, a, gravity=G) for q, v, a in zip(qs, vs, acs)])
    assert rel_err(ours.torques(), tau) <= 1e-12


def test_regressor_equals_pinocchios_on_a_random_tree():
    tree = random_tree(7, n=8, kinds=("Revolute", "Prismatic", "Spherical", "Fixed"))
    model = build_model(tree)
    pm, _ = build_pinocchio(tree, G)
    rng = np.random.default_rng(4)
    states = [random_state(model, rng) for _ in range(6)]
    qs = np.array([s[0] for s in states])
    vs = np.array([s[1] for s in states])
    acs = rng.normal(size=vs.shape)
    ours = ident.torque_regressor(model, qs, vs, acs, gravity=G)
    e = record("identification: random tree regressor vs Pinocchio", rel_err(ours.data, pin_regressor(pm, qs, vs, acs)))
    assert e <= 1e-12


def test_base_parameters_hold_for_pinocchios_regressor():
    pm = pin.buildModelFromUrdf(str(pmd.robots.urdf_path("panda")))
    pm.gravity.linear = G
    model = pmd.example_robot("panda")
    qs, vs, acs = panda_states(pm, 60, 2)
    base = ident.base_parameters(ident.torque_regressor(model, qs, vs, acs, gravity=G))
    y = pin_regressor(pm, qs, vs, acs)
    # The rank is Pinocchio's regressor's (unit columns, SVD), and every column of it is the
    # combination of the independent ones that the base parameters name.
    norms = np.linalg.norm(y, axis=0)
    yn = y[:, norms > 1e-11 * norms.max()]
    sv = np.linalg.svd(yn / np.linalg.norm(yn, axis=0), compute_uv=False)
    assert base.rank == int(np.sum(sv > 1e-8 * sv[0]))
    assert rel_err(y[:, base.independent] @ base.map, y) <= 1e-10
    # Least squares on Pinocchio's base regressor and torques gives K π.
    tau = np.concatenate([pin.rnea(pm, pm.createData(), q, v, a) for q, v, a in zip(qs, vs, acs)])
    beta = np.linalg.lstsq(y[:, base.independent], tau, rcond=None)[0]
    assert rel_err(beta, base.of(pin_parameters(pm))) <= 1e-9
    assert base.names[0].startswith(pmd.example_robot("panda").link_names[0]) or "." in base.names[0]


def test_ols_recovers_panda_base_parameters_from_exact_data():
    model = pmd.example_robot("panda")
    pm = pin.buildModelFromUrdf(str(pmd.robots.urdf_path("panda")))
    qs, vs, acs = panda_states(pm, 80, 3)
    tau = np.array([pin.rnea(pm, pm.createData(), q, v, a) for q, v, a in zip(qs, vs, acs)])
    res = pmd.identify(model, (qs, vs, acs, tau), method="ols", gravity=pm.gravity.linear)
    truth = res.base.of(pin_parameters(pm))
    e = record("identification: panda OLS base parameters, exact data", rel_err(res.base_values, truth))
    assert e <= 1e-9
    assert res.base.rank == res.structural_rank


# ------------------------------------------------------------------------------ a cells chain

BOX = np.array([[-0.05, -0.05, 0.0], [0.05, 0.05, 0.4]])


def cell_chain(rng, n=3):
    """A chain whose bodies are made of non-negative cells in BOX (so the cells' method can
    represent them exactly), revolute joints about varied axes."""
    centres, side = _cells(27)
    model = pmd.Model()
    parent = -1
    axes = ([0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 1, 0])
    for k in range(n):
        m = rng.uniform(0.0, 1.0, len(centres))
        params = sum(mk * _cube(c, side) for mk, c in zip(m, centres))
        b = ident.body_of(f"l{k}", params)
        body = pmd.RigidBody(b.mass, b.com, b.inertia)
        parent = model.add_body(body, pmd.Revolute(axes[k]), parent, translation=[0, 0, 0.4 if k else 0.0], name=f"l{k}")
    return model


def _cells(count):
    span = BOX[1] - BOX[0]
    side = float((np.prod(span) / count) ** (1 / 3))
    n = np.maximum(np.floor(span / side * (1 + 1e-12)).astype(int), 1)
    axes = [BOX[0][i] + (np.arange(n[i]) + 0.5) * span[i] / n[i] for i in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3), float(np.min(span / n))


def _cube(c, side):
    i = (c @ c + side**2 / 6) * np.eye(3) - np.outer(c, c)
    return np.array([1.0, *c, i[0, 0], i[0, 1], i[1, 1], i[0, 2], i[1, 2], i[2, 2]])


def chain_data(model, n, seed, extra=None):
    """Random states and the exact joint forces of ``model`` (plus ``extra(v, a)``)."""
    rng = np.random.default_rng(seed)
    qs = rng.uniform(-np.pi, np.pi, (n, model.nq))
    vs, acs = rng.normal(size=(n, model.nv)), rng.normal(size=(n, model.nv))
    tau = np.array([model.inverse_dynamics(q, v, a, gravity=G) for q, v, a in zip(qs, vs, acs)])
    if extra is not None:
        tau = tau + extra(vs, acs)
    return qs, vs, acs, tau


@pytest.mark.parametrize("method", ["ols", "cells"])
def test_exact_data_recover_the_base_parameters(method):
    model = cell_chain(np.random.default_rng(5))
    data = chain_data(model, 60, 6)
    env = {k: BOX for k in model.link_names}
    res = pmd.identify(model, data, method=method, envelopes=env, cells=27, gravity=G)
    truth = ident.torque_regressor(model, *data[:3], gravity=G).values
    e = record(f"identification: chain {method} base parameters, exact data", rel_err(res.base_values, res.base.of(truth)))
    assert e <= 1e-9
    if method == "cells":
        assert res.physical and all(b.inside_envelope for b in res.bodies.values())
        assert res.model is not None


def test_friction_and_armature_recovered_on_a_chain():
    model = cell_chain(np.random.default_rng(8))
    arm = np.array([0.05, 0.02, 0.01])
    fv, fc = np.array([0.3, 0.2, 0.1]), np.array([0.5, 0.25, 0.05])
    for k, name in enumerate(model.link_names):
        model.set_armature(name, arm[k])
    data = chain_data(model, 80, 9, lambda v, a: fv * v + fc * np.sign(v))
    reg = ident.torque_regressor(model, *data[:3], gravity=G, friction=True, armature=True)
    truth = reg.values.copy()
    truth[[reg.names.index(f"{k}.fv") for k in model.link_names]] = fv
    truth[[reg.names.index(f"{k}.fc") for k in model.link_names]] = fc
    # The starting guess knows nothing of the armature (the model's own values would).
    prior = reg.values.copy()
    prior[[reg.names.index(f"{k}.armature") for k in model.link_names]] = 0.0
    for method in ("ols", "cells"):
        res = pmd.identify(model, data, method=method, friction=True, armature=True, prior=prior,
                           envelopes={k: BOX for k in model.link_names}, cells=27, gravity=G)
        e = record(f"identification: chain {method} base parameters with friction and armature", rel_err(res.base_values, res.base.of(truth)))
        assert e <= 1e-9
        assert rel_err([res.friction[k]["viscous"] for k in model.link_names], fv) <= 1e-9, method
        assert rel_err([res.friction[k]["coulomb"] for k in model.link_names], fc) <= 1e-9, method
        # An armature that is a base parameter by itself is recovered as such; the others
        # (e.g. the first joint's, about a fixed vertical axis) only add to a link's inertia.
        alone = [k for k, n in enumerate(model.link_names) if f"{n}.armature" in res.base.names]
        assert alone, res.base.names
        got = np.array([res.armature[model.link_names[k]] for k in alone])
        assert rel_err(got, arm[alone]) <= 1e-9, (method, got)


# ------------------------------------------------------------------------------ noisy Panda


def panda_arm(tmp_path):
    """The Panda with its fingers welded (7 moving links), from its URDF."""
    text = pmd.robots.urdf_path("panda").read_text()
    for j in ("panda_finger_joint1", "panda_finger_joint2"):
        head = f'<joint name="{j}" type="prismatic">'
        assert head in text
        text = text.replace(head, f'<joint name="{j}" type="fixed">')
    path = tmp_path / "panda_arm.urdf"
    path.write_text(text)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
        return pmd.Model.from_urdf(str(path), package_dirs=[str(pmd.robots.directory().parent.parent)])


def noisy(model, traj, rng, sigma=None):
    tau = np.array([model.inverse_dynamics(q, v, a, gravity=G) for q, v, a in zip(traj.q, traj.v, traj.a)])
    if sigma is None:
        sigma = 0.01 * np.sqrt(np.mean(tau**2, axis=0))
    return tau + rng.normal(size=tau.shape) * sigma, sigma


def test_panda_cells_are_physical_and_predict_held_out_torques(tmp_path):
    model = panda_arm(tmp_path)
    assert model.nv == 7
    rng = np.random.default_rng(11)
    train = pmd.excitation_trajectory(model, 10.0, harmonics=4, rate=100, iterations=20, seed=1, gravity=G)
    test = pmd.excitation_trajectory(model, 10.0, harmonics=4, rate=50, iterations=0, seed=2, gravity=G)
    tau, sigma = noisy(model, train, rng)
    tau_test, _ = noisy(model, test, rng, sigma)
    # A perturbed starting guess: every parameter off by up to 20 %.
    values = ident.torque_regressor(model, train.q[:1], train.v[:1], train.a[:1]).values
    prior = values * (1 + 0.2 * rng.uniform(-1, 1, values.shape))
    data = (train.q, train.v, train.a, tau)
    cells = pmd.identify(model, data, method="cells", noise=sigma, prior=prior, prior_weight=1e-6, gravity=G)
    for name, body in cells.bodies.items():
        assert body.physical, (name, body.pseudo_inertia_min)
        assert body.inside_envelope, name
    held = ident.validate(cells, model, (test.q, test.v, test.a, tau_test), gravity=G)
    for j in range(model.nv):
        record(f"identification: panda cells held-out RMS / noise, joint {j}", held.rms[j] / sigma[j])
    assert np.all(held.rms <= 1.1 * sigma), held.rms / sigma
    # Plain least squares on the same data: some body cannot exist.
    ols = pmd.identify(model, data, method="ols", noise=sigma, prior=prior, gravity=G)
    bad = [n for n, b in ols.bodies.items() if not b.physical]
    assert bad, {n: b.pseudo_inertia_min for n, b in ols.bodies.items()}
    assert ols.model is None and "not a rigid body" in ols.model_error


# ------------------------------------------------------------------------------ bad input


def test_too_few_samples_name_the_unidentifiable_parameters():
    model = cell_chain(np.random.default_rng(5))
    data = chain_data(model, 2, 6)
    with pytest.raises(pmd.errors.InvalidInputError, match=r"data: .*not identifiable from it: l\d\."):
        pmd.identify(model, data, method="ols", gravity=G)


def test_bad_data_is_refused_naming_the_argument():
    model = cell_chain(np.random.default_rng(5))
    q, v, a, tau = chain_data(model, 20, 6)
    with pytest.raises(pmd.errors.InvalidInputError, match=r"data: expected q, v, a and tau of the same length"):
        pmd.identify(model, (q, v, a, tau[:-1]), method="ols")
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(pmd.errors.InvalidInputError, match=r"^v: expected finite numbers, got nan at index \(3, 1\)"):
        pmd.identify(model, (q, bad, a, tau), method="ols")
    with pytest.raises(pmd.errors.InvalidInputError, match=r"bodies: expected names of moving links .* got \['nope'\]"):
        pmd.identify(model, (q, v, a, tau), method="ols", bodies=["nope"])
    with pytest.raises(pmd.errors.InvalidInputError, match=r"method: expected one of"):
        pmd.identify(model, (q, v, a, tau), method="sdp")
    with pytest.raises(pmd.errors.InvalidInputError, match=r"tau: expected an \(N, 3\) array"):
        pmd.identify(model, (q, v, a, tau[:, :2]), method="ols")
    with pytest.raises(pmd.errors.InvalidInputError, match=r"t: expected uniformly spaced"):
        pmd.identify(model, (np.r_[0.0, np.cumsum(np.random.default_rng(0).uniform(0.1, 0.2, 19))], q, tau), method="ols")


# ------------------------------------------------------------------------------ excitation, filter


def test_excitation_stays_within_limits_and_writes_its_csv(tmp_path):
    model = pmd.example_robot("panda")
    exc = pmd.excitation_trajectory(model, 6.0, harmonics=3, rate=200, acceleration=4.0, iterations=5, seed=2, csv=tmp_path / "e.csv")
    limits = np.array(list(model.joint_limits().values()))
    lo, hi, vmax = limits[:, 0], limits[:, 1], limits[:, 3]
    assert np.all(exc.q >= lo - 1e-12) and np.all(exc.q <= hi + 1e-12)
    assert np.all(np.abs(exc.v) <= vmax) and np.all(np.abs(exc.a) <= 4.0)
    # v and a are the derivatives of q (central differences of the sampled series).
    dt = exc.t[1] - exc.t[0]
    assert rel_err((exc.q[2:] - exc.q[:-2]) / (2 * dt), exc.v[1:-1]) <= 1e-3
    assert rel_err((exc.v[2:] - exc.v[:-2]) / (2 * dt), exc.a[1:-1]) <= 1e-3
    table = np.loadtxt(tmp_path / "e.csv", delimiter=",", skiprows=1)
    assert table.shape == (len(exc.t), 1 + 3 * model.nv)
    assert rel_err(table[:, 1 : 1 + model.nv], exc.q) <= 1e-9
    # Periodic: the series is the same one period later.
    q1, _, _ = ident.fourier(exc.coefficients, exc.offsets, exc.t + 6.0, 2 * np.pi / 6.0)
    assert rel_err(q1, exc.q) <= 1e-12


def test_savgol_differentiates_a_polynomial_exactly_and_a_sine_closely():
    t = np.linspace(0.0, 2.0, 401)
    x = np.column_stack([1 + 2 * t - 3 * t**2 + 0.5 * t**3, np.sin(3 * t)])
    s, v, a = ident.savgol(t, x, window=21, order=3)
    # A cubic is its own fit: exact to rounding everywhere, the ends included.
    assert np.allclose(v[:, 0], 2 - 6 * t + 1.5 * t**2, atol=1e-9)
    assert np.allclose(a[:, 0], -6 + 3 * t, atol=1e-7)
    assert np.max(np.abs(v[:, 1] - 3 * np.cos(3 * t))) <= 1e-3
    assert np.max(np.abs(a[:, 1] + 9 * np.sin(3 * t))) <= 5e-2
