"""Issue 29, third round: partial results of interrupted analyses (R2-10), wording of
interrupts and refusals, and refusals moved up front. Each test is a defect the round
found (it fails on the main of 2026-11-26); the contract (BRIEF.md): a ``pmd.errors``
exception (``TypeError`` for a wrong Python type) naming the argument, the form expected
and what was given; interrupted and failed runs keep what they computed."""

from __future__ import annotations

import re

import numpy as np
import pointmass_dyn as pmd
import pytest
from ctrl_c import CtrlC
from pointmass_dyn.errors import InvalidInputError, UrdfError

G = np.array([0.0, -9.81, 0.0])
LONG_NUMBER = re.compile(r"\d{25,}")


@pytest.fixture(scope="module")
def fourbar():
    return pmd.load_scene("fourbar")


@pytest.fixture(scope="module")
def motion(fourbar):
    return pmd.prescribed_motion(fourbar.model, "crank", speed=30.0, samples=24,
                                 q_guess=fourbar.q0, gravity=G)


def _same_instants(part, full):
    """The partial analysis is the full one's first instants, array by array."""
    n = len(part.t)
    for name in ("t", "q", "v", "a", "tau", "bearing", "cut"):
        np.testing.assert_allclose(getattr(part, name), getattr(full, name)[:n], rtol=0,
                                   atol=1e-9, err_msg=name)
    np.testing.assert_allclose(part.shaking.force, full.shaking.force[:n], rtol=0, atol=1e-9)
    np.testing.assert_allclose(part.shaking.moment, full.shaking.moment[:n], rtol=0, atol=1e-9)


# --------------------------------------------------------------------------------------------
# R2-10. prescribed_motion, analyze_motion, point_regressor, shaking and work_precision
# stopped by Ctrl-C or a raising progress answered at once but kept nothing.
# --------------------------------------------------------------------------------------------
def test_prescribed_motion_stopped_by_progress_keeps_the_instants_done(fourbar):
    kw = dict(speed=30.0, samples=300, q_guess=fourbar.q0, gravity=G)
    full = pmd.prescribed_motion(fourbar.model, "crank", **kw)
    calls = []

    def progress(done, total):
        calls.append(done)
        if len(calls) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as info:
        pmd.prescribed_motion(fourbar.model, "crank", progress=progress, **kw)
    part = info.value.result
    assert isinstance(part, pmd.MotionAnalysis) and not part.success
    assert 0 < len(part.t) < 300 and 2 * len(part.t) == calls[-1]
    assert part.t_reached == part.t[-1]
    assert f"stopped after {len(part.t)} of 300 instants" in part.message
    assert "interrupted" in part.message and "in this exception's .result" in info.value.__notes__[-1]
    _same_instants(part, full)
    np.testing.assert_array_equal(part.input, full.input[: len(part.t)])
    assert full.success and full.message == "complete" and full.t_reached == full.t[-1]


def test_prescribed_motion_stopped_by_ctrl_c_keeps_the_instants_done(fourbar):
    ctrl_c = CtrlC(armed=False)

    def progress(done, total):
        if done >= 2 * 64:  # the second report (every 64th instant): 64 instants done
            ctrl_c.arm()

    part = ctrl_c.run(lambda: pmd.prescribed_motion(
        fourbar.model, "crank", speed=30.0, samples=10**6, q_guess=fourbar.q0, gravity=G,
        progress=progress)).result
    assert not part.success and 64 <= len(part.t) < 10**6
    # An independent check of the instants kept: every one is closed, and the driving torque
    # reproduces its accelerations through forward dynamics.
    m = fourbar.model
    for k in range(0, len(part.t), max(1, len(part.t) // 5)):
        assert np.max(np.abs(m.constraint_residual(part.q[k]))) < 1e-9
        a = m.forward_dynamics(part.q[k], part.v[k], part.tau[k], gravity=G)
        np.testing.assert_allclose(a, part.a[k], rtol=1e-8, atol=1e-8 * np.abs(part.a[k]).max())
    assert part.message.startswith(f"stopped after {len(part.t)} of 1000000 instants")


def test_analyze_motion_stopped_by_progress_keeps_the_states_done(fourbar, motion):
    seen = []

    def progress(done, total):
        seen.append(done)
        raise RuntimeError("cancelled by the caller")

    many = [np.tile(x, (10, 1)) for x in (motion.q, motion.v, motion.a)]
    t = np.arange(len(many[0])) * 0.01
    with pytest.raises(RuntimeError, match="cancelled by the caller") as info:
        pmd.analyze_motion(fourbar.model, t, *many, actuated=["crank"], gravity=G,
                           progress=progress)
    part = info.value.result
    assert not part.success and len(part.t) == 0 and part.t_reached is None
    assert "RuntimeError: cancelled by the caller" in part.message


def _stopped_after_some_states(name, call):
    """The partial result of ``call`` stopped by Ctrl-C after some states. The press is
    heard by the call's own polls of the signal handlers, at most one per state, and raises
    at the n-th; the up-front check of the states polls too (and has nothing to keep), so n
    doubles until the press lands in the computation after a state done (no delays: a
    loaded machine changes n, not the outcome)."""
    part = None
    for polls in (1, 2, 4, 8, 16, 32):
        error = CtrlC(inside=name, polls=polls).attempt(call)
        if error is None:
            pytest.fail(f"{name} ended before its poll {polls} heard Ctrl-C (last: {part})")
        part = getattr(error, "result", None)
        if part is not None and part["states"] > 0:
            return part
    pytest.fail(f"{name}: no Ctrl-C kept a state done (last: {part})")


def test_point_regressor_and_shaking_stopped_by_ctrl_c_keep_the_states_done():
    # A model without loops: a loop model's check of the states closes each one's loops, as
    # long as the computation itself. Enough states for any CPU to poll (every 50 ms).
    m = pmd.load_scene("chain7").model
    rng = np.random.default_rng(7)
    q, v, a = (np.tile(rng.uniform(-1, 1, (100, n)), (4000, 1)) for n in (m.nq, m.nv, m.nv))
    points = [(m.body_names[-1], [0.01, 0.0, 0.0])]
    for name, call in (
        ("point_regressor", lambda: m.point_regressor(q, v, a, points=points, gravity=G)),
        ("shaking", lambda: m.shaking(q, v, a)),
    ):
        part = _stopped_after_some_states(name, call)
        k = part["states"]
        assert 0 < k < len(q) and f"{name} stopped after {k} of {len(q)} states" in part["message"]
        if name == "point_regressor":
            assert part["generalized"].shape == (k, 1, m.nv)
            # The rows kept are what the same states give alone.
            ref = m.point_regressor(q[:k], v[:k], a[:k], points=points, gravity=G)
            np.testing.assert_allclose(part["generalized"], ref["generalized"], rtol=0, atol=0)
        else:
            assert part["force"].shape == (k, 3)
            # −Σ m a of the point masses, as the one-state call gives it.
            f, _ = m.shaking(q[k - 1], v[k - 1], a[k - 1])
            np.testing.assert_allclose(part["force"][-1], f, rtol=0, atol=0)


def test_work_precision_stopped_by_progress_keeps_the_rows_measured():
    calls = []

    def progress(msg):
        calls.append(msg)
        if "at 1e-05" in msg:
            raise KeyboardInterrupt

    kw = dict(t_end=0.5, repeats=1, scipy=False, rk4=False, n_dense=11)
    with pytest.raises(KeyboardInterrupt) as info:
        pmd.work_precision("pendulum_planar", [1e-3, 1e-4, 1e-5, 1e-6], progress=progress, **kw)
    part = info.value.result
    assert not part.success and [r["tol"] for r in part.rows] == [1e-3, 1e-4]
    assert "simulate at 1e-05" in part.message and "after 2 rows" in part.message
    # The rows kept are the ones a run of those tolerances alone measures (errors against the
    # DOP853 reference do not depend on the timing).
    alone = pmd.work_precision("pendulum_planar", [1e-3, 1e-4], **kw)
    for r, s in zip(part.rows, alone.rows):
        assert r["nfev"] == s["nfev"] and r["err_final"] == pytest.approx(s["err_final"], rel=1e-9)


def test_work_precision_stopped_by_ctrl_c_keeps_the_reference_check():
    # Ctrl-C pressed once the second tolerance's measurement has begun: the reference, its
    # check and the first row are done, and are what an uninterrupted run measures.
    ctrl_c = CtrlC(armed=False)

    def progress(msg):
        if "simulate at 0.0001" in msg:
            ctrl_c.arm()

    kw = dict(t_end=0.5, repeats=1, scipy=False, rk4=False, n_dense=11)
    part = ctrl_c.run(lambda: pmd.work_precision(
        "pendulum_planar", [1e-3, 1e-4, 1e-5], progress=progress, **kw)).result
    assert not part.success and "interrupted" in part.message
    assert part.scene == "pendulum_planar" and "simulate at 0.0001" in part.message
    full = pmd.work_precision("pendulum_planar", [1e-3, 1e-4, 1e-5], **kw)
    assert set(part.reference_check) == set(full.reference_check) and "err_final" in full.reference_check
    for key, value in full.reference_check.items():
        if key.startswith("err") or key == "energy_scale":
            assert part.reference_check[key] == pytest.approx(value, rel=1e-9), key
        else:
            assert part.reference_check[key] == value, key
    assert [r["tol"] for r in part.rows] == [1e-3]
    first, again = part.rows[0], full.rows[0]
    assert first["nfev"] == again["nfev"] and first["steps"] == again["steps"]
    for key in ("err_final", "err_dense", "err_energy"):
        assert first[key] == pytest.approx(again[key], rel=1e-9), key


# --------------------------------------------------------------------------------------------
# Wording: interrupts name their cause; a batch names the run its params broke.
# --------------------------------------------------------------------------------------------
def _contact_ball():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(2.0, [0, 0, 0], np.eye(3) * 0.002), pmd.Prismatic([0, 0, 1]),
               name="ball")
    contact = pmd.GroundContact([("ball", [0, 0, 0], 0.05)], stiffness=2e5, damping=5e5,
                                friction=0.0)
    return pmd.Scene(m, q0=[0.1], v0=[0.0], effects=[contact, pmd.Gravity([0, 0, -9.81])])


@pytest.mark.parametrize("method", ["RK45", "Radau"])
def test_a_contact_run_stopped_by_progress_says_interrupted_not_failed(method):
    # Was "the right-hand side failed at t = …: interrupted".
    calls = []

    def progress(t):
        calls.append(t)
        if len(calls) > 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as info:
        pmd.simulate(_contact_ball(), (0, 30), method=method, rtol=1e-10, atol=1e-12,
                     progress=progress, progress_interval=0.0)
    r = info.value.result
    assert r.message.startswith("interrupted at t = ") and "failed" not in r.message
    assert "Ctrl-C (or a KeyboardInterrupt raised by progress)" in r.message
    assert 0 < r.t_reached < 30


def test_a_batch_stopped_by_progress_names_the_real_reason():
    # The runs said "KeyboardInterrupt: the batch was stopped …" for a RuntimeError.
    scene = pmd.load_scene("chain7")

    def progress(done, total):
        if done >= 1:
            raise RuntimeError("cancelled")

    with pytest.raises(RuntimeError, match="cancelled") as info:
        pmd.simulate_batch(scene, (0, 30), q0=np.tile(scene.q0, (6, 1)), rtol=1e-11,
                           atol=1e-11, progress=progress, threads=2)
    messages = info.value.result.message
    cut = [m for m in messages if not m.startswith("reached the end")]
    assert cut and all("RuntimeError: cancelled, raised by progress" in m for m in cut)
    assert not any("KeyboardInterrupt" in m for m in messages)


def test_batch_params_errors_name_the_run():
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(pmd.errors.InertiaError, match=r"params \(run 2\): mass: .*got -1"):
        pmd.simulate_batch(scene, (0, 0.1), params={"rod.mass": [1.0, 2.0, -1.0]})
    with pytest.raises(InvalidInputError, match=r"params \(run 1\): gravity: .*NaN"):
        pmd.simulate_batch(scene, (0, 0.1), params={"gravity": [[0, 0, -9.8], [0, 0, np.nan]]})


def test_torque_limit_message_says_inf_is_allowed():
    pmd.JointTorque(None, 1.0, limit=np.inf)  # accepted: no limit
    for bad in (np.nan, -1.0, [1.0, np.nan]):
        with pytest.raises(InvalidInputError, match=r"limit: expected numbers > 0.*inf: no limit"):
            pmd.JointTorque(None, 1.0, limit=bad)


@pytest.mark.parametrize("x", [1e-300, -1e-300, 1e300, -1e300, 1e-320])
def test_error_messages_write_extreme_numbers_in_exponent_form(x):
    # Rust's "{}" wrote 1e-300 as 0.000…0001 with 300 zeros.
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]), name="a")
    gc = dict(stiffness=1e4, damping=10.0, friction=0.5)
    calls = [
        lambda: pmd.RigidBody(-abs(x), [0, 0, 0], np.eye(3)),
        lambda: pmd.simulate(pmd.Scene(m), (0, 1), rtol=-abs(x)),
        lambda: pmd.simulate(pmd.Scene(m), (0, 1), first_step=-abs(x)),
        lambda: pmd.simulate(pmd.Scene(m), (0, 1), t_eval=[-abs(x) - 1e-3]),
        lambda: pmd.Scene(m, effects=[pmd.GroundContact([("a", [0, 0, 0], 0.1)],
                                                        **{**gc, "damping": -abs(x)})]),
        lambda: pmd.JointLimit(lower=1.0, upper=1.0 - abs(x) if abs(x) > 1 else -abs(x),
                               stiffness=1.0, damping=1.0),
        lambda: m.set_armature("a", -abs(x)),
    ]
    for call in calls:
        with pytest.raises(pmd.errors.PointMassDynError) as info:
            call()
        assert not LONG_NUMBER.search(str(info.value)), str(info.value)[:200]


def test_joint_limit_on_a_model_without_1dof_joints_says_so():
    # Was "lower: expected 0 values".
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.01), pmd.Spherical(), name="ball")
    with pytest.raises(InvalidInputError, match="a model that has no 1-dof joints"):
        pmd.Scene(m, effects=[pmd.JointLimit(lower=-1.0, upper=1.0, stiffness=1.0, damping=0.1)])


# --------------------------------------------------------------------------------------------
# Up-front refusals (they failed at run time, or not at all).
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("bound", [1e308, -1e300, 2e9])
def test_joint_limit_bounds_beyond_any_mechanism_are_refused_up_front(bound):
    with pytest.raises(InvalidInputError, match=r"lower: expected numbers within ±1e9 \(rad or m\), or ±inf"):
        pmd.JointLimit(lower=bound, upper=np.inf, stiffness=1e3, damping=1.0)
    pmd.JointLimit(lower=-np.inf, upper=1e9, stiffness=1e3, damping=1.0)  # the bound itself


@pytest.mark.parametrize("where", ["offset", "radius", "height"])
def test_contact_lengths_beyond_any_mechanism_are_refused_up_front(where):
    point, kw = ("ball", [0, 0, 0], 0.05), dict(stiffness=2e5, damping=5e5, friction=0.0)
    if where == "offset":
        point = ("ball", [1e300, 0, 0], 0.05)
    elif where == "radius":
        point = ("ball", [0, 0, 0], 1e300)
    else:
        kw["height"] = -1e300
    with pytest.raises(InvalidInputError, match=r"within ±1e6 m|in \[0, 1e6\] m"):
        pmd.GroundContact([point], **kw)


def test_contact_forces_at_a_non_finite_state_are_refused():
    scene = _contact_ball()

    class Result:
        q = np.array([[0.1], [np.nan]])
        v = np.array([[0.0], [0.0]])

    with pytest.raises(InvalidInputError, match=r"q: expected finite states, got NaN in state 1"):
        pmd.contact_forces(scene, Result)


def test_balance_flags_and_factors_are_checked_always(motion):
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)]
    with pytest.raises(InvalidInputError, match="least_mass: expected True or False, got 'yes'"):
        pmd.balance(motion, counterweights=ring, least_mass="yes")
    for bad in ((np.nan, 1.0), (2.0, 1.0), (1.0,), "ab"):
        with pytest.raises(InvalidInputError, match="link_mass: expected factors"):
            pmd.balance(motion, counterweights=ring, link_mass=bad)


def test_a_second_mimic_in_one_urdf_joint_is_refused(tmp_path):
    urdf = """<robot name="r">
      <link name="base"/>
      <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="b"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="jb" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/>
        <mimic joint="ja" multiplier="2"/><mimic joint="ja" multiplier="3"/></joint>
    </robot>"""
    path = tmp_path / "two_mimics.urdf"
    path.write_text(urdf)
    with pytest.raises(UrdfError, match="a second <mimic>: a joint mimics at most one joint"):
        pmd.Model.from_urdf(str(path), mimic=True)
    path.write_text(urdf.replace('<mimic joint="ja" multiplier="3"/>', ""))
    m = pmd.Model.from_urdf(str(path), mimic=True)
    assert len(m.couplings) == 1


def test_an_empty_loop_name_is_refused(fourbar):
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]), name="a")
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]),
               parent="a", translation=[1, 0, 0], name="b")
    for name in ("", "  "):
        with pytest.raises(InvalidInputError, match="name: expected a non-empty loop name"):
            m.add_loop("b", -1, pmd.Revolute([0, 0, 1]), translation_a=[1, 0, 0],
                       translation_b=[1, 0, 0], name=name)
    assert m.nloops == 0
    m.add_loop("b", -1, pmd.Revolute([0, 0, 1]), translation_a=[1, 0, 0], translation_b=[1, 0, 0])
    assert m.nloops == 1 and m.loop_names[0]


def test_empty_body_and_coupling_names_are_refused():
    # Found by this round's probes: a body and a coupling named "" (unnamed in every listing).
    m = pmd.Model()
    body = pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01)
    with pytest.raises(InvalidInputError, match="name: expected a non-empty body name"):
        m.add_body(body, pmd.Revolute([0, 0, 1]), name="")
    m.add_body(body, pmd.Revolute([0, 0, 1]), name="a")
    m.add_body(body, pmd.Revolute([0, 0, 1]), parent="a", translation=[1, 0, 0], name="b")
    with pytest.raises(InvalidInputError, match="name: expected a non-empty coupling name"):
        m.add_coupling("b", "a", ratio=2.0, name=" ")
    assert m.couplings == []
    m.add_coupling("b", "a", ratio=2.0)
    assert m.couplings[0][0]


def test_blank_effect_names_are_refused_by_the_scene():
    # An effect's name is its output key: "" and "  " would be unnamed columns.
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]),
               name="a")
    for name in ("", "  "):
        with pytest.raises(InvalidInputError, match=r"effects\[1\]\.name: expected a non-empty"):
            pmd.Scene(m, effects=[pmd.Gravity([0, 0, -9.81]), pmd.Spring("a", 1.0, name=name)])
    spring = pmd.Spring("a", 1.0, name="k")
    pmd.Scene(m, effects=[spring])
    assert "name='k'" in repr(spring)


# --------------------------------------------------------------------------------------------
# Found by tests/test_fuzz_api_wave.py (this round's fuzzing of the newer entry points).
# --------------------------------------------------------------------------------------------
@pytest.mark.filterwarnings("error::numpy.exceptions.ComplexWarning")
def test_counterweight_ring_checks_its_centre_radius_and_normal():
    # A string centre was a builtin ValueError, a complex one lost its imaginary part, a
    # radius of NaN gave NaN candidates, a normal of 1e300 overflowed its norm.
    ring = pmd.Counterweight.ring
    for center in ("", [0, 0], [0, 0, np.nan], [0j, 1j, 0]):
        with pytest.raises(InvalidInputError, match="center: expected a finite"):
            ring("crank", center, 0.02, 4)
    for radius in (np.nan, -0.01, 0.0, "0.02", np.inf):
        with pytest.raises(InvalidInputError, match="radius: expected a finite number > 0"):
            ring("crank", [0, 0, 0], radius, 4)
    for normal in ("", [1j, 0, 1], [0, 0, 0]):
        with pytest.raises(InvalidInputError, match="normal: expected a finite non-zero"):
            ring("crank", [0, 0, 0], 0.02, 4, normal=normal)
    big = ring("crank", [0, 0, 0], 0.02, 4, normal=[0, 0, 1e300])
    flat = ring("crank", [0, 0, 0], 0.02, 4, normal=[0, 0, 1])
    np.testing.assert_allclose(big.points, flat.points, rtol=0, atol=1e-15)


def test_balance_objective_and_limits_must_be_dicts(motion):
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)]
    # dict("0.3") was a builtin ValueError.
    for arg in ("objective", "limits"):
        with pytest.raises(InvalidInputError, match=f"{arg}: expected None or a dict"):
            pmd.balance(motion, counterweights=ring, **{arg: "0.3"})


def test_link_shape_envelopes_of_strings_are_refused(fourbar):
    # np.asarray("", float): a builtin ValueError from LinkShape.cells.
    with pytest.raises(InvalidInputError, match=r"box: expected \(lower, upper\) corners"):
        pmd.LinkShape("crank", box="", cell=0.01).cells(fourbar.model)
    with pytest.raises(InvalidInputError, match="polygon: expected"):
        pmd.LinkShape("crank", polygon="ab", z=(0, 1), cell=0.01).cells(fourbar.model)


@pytest.mark.filterwarnings("error::numpy.exceptions.ComplexWarning")
def test_contact_forces_refuses_states_it_cannot_read():
    scene = _contact_ball()
    bad = [
        (np.array([[""]]), np.zeros((1, 1)), "result: expected a result with numeric q"),
        (np.array([[0.1 + 1j]]), np.zeros((1, 1)), "result: expected real q and v"),
    ]
    for q, v, message in bad:
        with pytest.raises(InvalidInputError, match=message):
            pmd.contact_forces(scene, type("R", (), {"q": q, "v": v}))


def test_contact_forces_at_a_zero_quaternion_or_an_overflowing_law_are_refused():
    # NaN positions for a zero quaternion; inf forces for a damping of 3e307 (both silent).
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.01), pmd.Spherical(), name="ball")
    contact = pmd.GroundContact([("ball", [0, 0, -0.1], 0.05)], stiffness=1e3, damping=3e307,
                                friction=0.0)
    scene = pmd.Scene(m, effects=[contact])

    class State:
        q = np.zeros((1, 4))
        v = np.zeros((1, 3))

    with pytest.raises(InvalidInputError, match=r"q \(state 0\): expected a quaternion"):
        pmd.contact_forces(scene, State)
    # A point 1.05 m deep moving into the ground at 10 m/s: c δ^e v overflows.
    State.q = np.array([[0.0, 0.0, 0.0, 1.0]])
    State.v = np.array([[0.0, 100.0, 0.0]])
    contact_low = pmd.GroundContact([("ball", [0.1, 0, 0], 0.05)], stiffness=1e3, damping=3e307,
                                    friction=0.0, height=1.0)
    with pytest.raises(pmd.errors.NumericalError, match=r"contact_state\['.*'\]: the result is not finite"):
        pmd.contact_forces(pmd.Scene(m, effects=[contact_low]), State)


def test_urdf_contact_spheres_of_nan_or_inf_are_refused(tmp_path):
    # float("inf") read a sphere of infinite radius, returned as it was.
    for radius, xyz in (("inf", "0 0 0"), ("nan", "0 0 0"), ("-0.1", "0 0 0"), ("0.1", "nan 0 0")):
        path = tmp_path / "r.urdf"
        path.write_text(
            f'<robot name="r"><link name="a"><collision><origin xyz="{xyz}"/><geometry>'
            f'<sphere radius="{radius}"/></geometry></collision></link></robot>')
        with pytest.raises(InvalidInputError, match="expected a finite <origin xyz> and a finite"):
            pmd.urdf_contact_points(path, ["a"])


def test_analyze_motion_refuses_arrays_it_cannot_read(fourbar):
    # Found by tests/test_fuzz_api.py: t = "" was NumPy's builtin ValueError.
    m, z = fourbar.model, np.zeros((1, fourbar.model.nv))
    for name, args in (("t", ("", z, z, z)), ("q", ([0.0], "ab", z, z)),
                       ("a", ([0.0], z, z, [["x", 1.0, 2.0]]))):
        with pytest.raises(InvalidInputError, match=f"{name}: expected an array of real numbers"):
            pmd.analyze_motion(m, *args, actuated=["crank"])
