"""The newer features under bad input, faults and interrupts (issue 29).

Each test reproduces one defect an adversarial round found and asserts what the standard asks
for: our own exception naming the argument, the right answer (against an independent
reference: an analytic rotation, MuJoCo's compiler, a fresh run), or the partial result.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G, rod_body
from pointmass_dyn.errors import (
    ClusterError,
    InvalidInputError,
    SingularityError,
)


@pytest.fixture(scope="module")
def fourbar_motion():
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(
        scene.model, "crank", speed=2 * np.pi, samples=36, q_guess=scene.q0, gravity=G
    )
    return scene, motion


def _run_limited(code: str, limit_bytes: int) -> subprocess.CompletedProcess:
    """``code`` in a fresh interpreter whose address space is capped at ``limit_bytes``."""
    prelude = textwrap.dedent(
        f"""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, ({limit_bytes}, {limit_bytes}))
        """
    )
    return subprocess.run(
        [sys.executable, "-c", prelude + textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=300,
    )


# --------------------------------------------------------------------------------------------
# 1. point_regressor with arrays beyond the memory: our error, the process lives.
# --------------------------------------------------------------------------------------------
def test_point_regressor_beyond_memory_is_out_of_memory_error():
    code = """
        import numpy as np, pointmass_dyn as pmd
        scene = pmd.load_scene("fourbar")
        mo = pmd.prescribed_motion(scene.model, "crank", speed=6.0, samples=36, q_guess=scene.q0)
        try:
            scene.model.point_regressor(mo.q, mo.v, mo.a, points=[("crank", [0.1, 0, 0])] * 10**6)
        except pmd.errors.OutOfMemoryError as e:
            print("OOM", "point_regressor" in str(e))
        """
    out = _run_limited(code, 2 << 30)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["OOM", "True"]


def test_point_regressor_still_agrees_with_point_motion(fourbar_motion):
    """The regressor moved into the core: its positions and accelerations are the point
    masses' own (point_motion, an independent path through the same kinematics)."""
    scene, mo = fourbar_motion
    model = scene.model
    k = 5
    pm = model.point_motion(mo.q[k], mo.v[k], mo.a[k])
    reg = model.point_regressor(mo.q[k], mo.v[k], mo.a[k])
    np.testing.assert_allclose(reg["positions"], pm["positions"].reshape(-1, 3), atol=1e-12)
    np.testing.assert_allclose(
        reg["accelerations"], pm["accelerations"].reshape(-1, 3), atol=1e-9
    )
    # generalized = J_pᵀ (a_p − g): a unit mass at every point needs these joint forces; over
    # all point masses weighted by their masses it is the inverse dynamics of the tree.
    w = pm["masses"].reshape(-1)
    tau_tree = np.einsum("p,pk->k", w, reg["generalized"])
    assert np.all(np.isfinite(tau_tree))


# --------------------------------------------------------------------------------------------
# 9. Quaternions far from unit norm: normalised safely, or refused saying why.
# --------------------------------------------------------------------------------------------
def _free_box():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(2.0, [0, 0, 0], np.diag([0.1, 0.2, 0.3])), pmd.FreeFlyer(),
               parent=-1, name="box")
    return m


@pytest.mark.parametrize("scale", [1e155, 1e300, 3.0, 1e-7])
def test_huge_quaternion_is_the_rotation_it_points_at(scale):
    m = _free_box()
    q = np.array([0.0, 0.0, 0.0, scale, 0.0, 0.0, 0.0])  # (x, y, z, w): half-turn about x
    rot = m.body_poses(q)["rotations"][0]
    np.testing.assert_allclose(rot, np.diag([1.0, -1.0, -1.0]), atol=1e-15)
    scene = pmd.Scene(m, q, np.zeros(6))
    np.testing.assert_allclose(scene.q0, [0, 0, 0, 1, 0, 0, 0], atol=1e-15)
    a = m.forward_dynamics(q, np.zeros(6), np.zeros(6), gravity=G)
    np.testing.assert_allclose(a[:3], [0.0, 0.0, 9.81], atol=1e-12)  # body axes: upside down


def test_tiny_quaternion_is_refused_with_the_bound():
    m = _free_box()
    with pytest.raises(InvalidInputError, match=r"norm at least 1e-8.*got.*norm 1\.000e-9"):
        m.body_poses([0, 0, 0, 1e-9, 0, 0, 0])


# --------------------------------------------------------------------------------------------
# 11. sweep's scheduler: our errors, within the stated timeout.
# --------------------------------------------------------------------------------------------
def test_sweep_unreachable_scheduler_is_our_error_within_the_timeout(monkeypatch):
    distributed = pytest.importorskip("distributed")
    import socket

    # What bounds the wait, not a clock: the one connection attempt is given the timeout,
    # and a malformed address is refused before any (no socket, no Client).
    attempts = []
    connect = socket.create_connection

    def create_connection(address, timeout=None, *args, **kwargs):
        attempts.append((address, timeout))
        return connect(address, timeout, *args, **kwargs)

    def no_client(*args, **kwargs):
        raise AssertionError("a Client was built for an address refused up front")

    monkeypatch.setattr(socket, "create_connection", create_connection)
    monkeypatch.setattr(distributed, "Client", no_client)
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(ClusterError, match=r"127\.0\.0\.1:1.*connect_timeout=1\.0"):
        pmd.sweep(scene, (0, 0.1), t_eval=[0, 0.1], scheduler="tcp://127.0.0.1:1",
                  connect_timeout=1.0)
    assert attempts == [(("127.0.0.1", 1), 1.0)]
    for bad in ("notanaddress", "foo://x:1", "tcp://host:abc"):
        with pytest.raises(InvalidInputError, match="scheduler"):
            pmd.sweep(scene, (0, 0.1), t_eval=[0, 0.1], scheduler=bad, connect_timeout=1.0)
    assert len(attempts) == 1
    with pytest.raises(InvalidInputError, match="connect_timeout"):
        pmd.sweep(scene, (0, 0.1), t_eval=[0, 0.1], scheduler="tcp://127.0.0.1:1",
                  connect_timeout=0)


# --------------------------------------------------------------------------------------------
# 17, 18. analyze_motion / prescribed_motion input checks.
# --------------------------------------------------------------------------------------------
def test_analyze_motion_refuses_arrays_of_other_lengths(fourbar_motion):
    scene, mo = fourbar_motion
    with pytest.raises(InvalidInputError, match=r"q: expected shape \(36, 3\).*\(35, 3\)"):
        pmd.analyze_motion(scene.model, mo.t, mo.q[:-1], mo.v, mo.a, actuated=["crank"])
    with pytest.raises(InvalidInputError, match=r"a: expected shape"):
        pmd.analyze_motion(scene.model, mo.t, mo.q, mo.v, mo.a[:, :2], actuated=["crank"])
    with pytest.raises(InvalidInputError, match="t: expected"):
        pmd.analyze_motion(scene.model, [], mo.q[:0], mo.v[:0], mo.a[:0], actuated=["crank"])


def test_prescribed_motion_refuses_empty_motions(fourbar_motion):
    scene, _ = fourbar_motion
    for revolutions in (0, -1, np.nan):
        with pytest.raises(InvalidInputError, match="revolutions"):
            pmd.prescribed_motion(scene.model, "crank", speed=1.0, revolutions=revolutions,
                                  q_guess=scene.q0)
    with pytest.raises(InvalidInputError, match="input"):
        pmd.prescribed_motion(scene.model, "crank", input=([], [], [], []), q_guess=scene.q0)
    with pytest.raises(InvalidInputError, match="input: expected finite"):
        pmd.prescribed_motion(scene.model, "crank", input=([0, 1], [0, np.nan], [1, 1], [0, 0]),
                              q_guess=scene.q0)


def test_prescribed_motion_reports_progress_to_the_end(fourbar_motion):
    scene, mo = fourbar_motion
    seen = []
    again = pmd.prescribed_motion(scene.model, "crank", speed=2 * np.pi, samples=200,
                                  q_guess=scene.q0, gravity=G,
                                  progress=lambda d, n: seen.append((d, n)))
    assert seen[-1] == (400, 400) and all(n == 400 for _, n in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen) and len(seen) >= 4
    assert again.q.shape == (200, 3)


# --------------------------------------------------------------------------------------------
# 21. to_mjcf of a model from_mujoco split (a body with two joints) is MJCF MuJoCo takes.
# --------------------------------------------------------------------------------------------
def test_to_mjcf_of_an_imported_two_joint_body_compiles_and_agrees():
    mujoco = pytest.importorskip("mujoco")
    xml = """
    <mujoco><option gravity="0 0 -9.81"/><worldbody>
      <body name="arm" pos="0 0 1" quat="0.9 0.1 0.3 0.2">
        <joint name="pitch" type="hinge" axis="0 1 0" pos="0.1 0 0"/>
        <joint name="slide" type="slide" axis="1 0 0.2"/>
        <geom type="capsule" size="0.05" fromto="0 0 0 0.5 0 0" mass="1.3"/>
        <body name="tip" pos="0.5 0 0">
          <joint name="roll" type="hinge" axis="1 0 0"/>
          <joint name="ball" type="ball" pos="0 0.05 0"/>
          <geom type="sphere" size="0.07" mass="0.4" pos="0.02 0.03 0"/>
        </body>
      </body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    ours = pmd.from_mujoco(m)
    assert ours.nbodies > 2  # split: massless parts between the joints
    back = mujoco.MjModel.from_xml_string(pmd.to_mjcf(ours, gravity=[0, 0, -9.81]))  # main: refused
    assert (back.nq, back.nv, back.njnt) == (m.nq, m.nv, m.njnt)
    rng = np.random.default_rng(3)
    d0, d1 = mujoco.MjData(m), mujoco.MjData(back)
    for _ in range(3):
        qpos = rng.normal(size=m.nq)
        qpos[3:7] /= np.linalg.norm(qpos[3:7])
        qvel = rng.normal(size=m.nv)
        for mm, dd in ((m, d0), (back, d1)):
            dd.qpos[:], dd.qvel[:] = qpos, qvel
            mujoco.mj_forward(mm, dd)
        np.testing.assert_allclose(d1.qacc, d0.qacc, rtol=1e-9, atol=1e-9)


# --------------------------------------------------------------------------------------------
# 22. Scene derivatives at a ZYZ singularity: SingularityError, as Model's.
# --------------------------------------------------------------------------------------------
def test_scene_derivatives_at_the_zyz_singularity_are_singularity_errors():
    m = pmd.Model()
    m.add_body(rod_body(), pmd.SphericalZYZ(), parent=-1, name="rod")
    scene = pmd.Scene(m, [0.1, 0.5, 0.2], np.zeros(3), effects=[pmd.Gravity(G)])
    q = np.array([0.1, 0.0, 0.2])
    with pytest.raises(SingularityError):
        m.forward_dynamics_derivatives(q, np.zeros(3), np.zeros(3))
    with pytest.raises(SingularityError, match="forward_dynamics_derivatives"):
        scene.forward_dynamics_derivatives(q, np.zeros(3))


# --------------------------------------------------------------------------------------------
# 26. from_urdf(repair=...): bools are not numbers.
# --------------------------------------------------------------------------------------------
def test_from_urdf_repair_bound_refuses_bools():
    urdf = pmd.scenes.resolve_scene_path("panda").with_suffix(".urdf")
    for key in ("bound_mass", "bound_inertia"):
        with pytest.raises(InvalidInputError, match=f"repair.{key}: expected a finite number"):
            pmd.Model.from_urdf(urdf, repair={key: True})
        with pytest.raises(InvalidInputError, match=f"repair.{key}"):
            pmd.Model.from_urdf(urdf, repair=pmd.InertiaRepair(**{key: True}))


# --------------------------------------------------------------------------------------------
# Smaller: solve_ivp(method="auto") checks a callable jac at the start, as Radau does.
# --------------------------------------------------------------------------------------------
def test_auto_checks_jac_even_without_switching():
    def fun(t, y):
        return -y

    with pytest.raises(InvalidInputError, match=r"jac\(t, y\)"):
        pmd.solve_ivp(fun, (0, 1), [1.0, 2.0], method="auto", jac=lambda t, y: np.eye(3))
    with pytest.raises(InvalidInputError, match=r"jac\(t0, y0\).*finite"):
        pmd.solve_ivp(fun, (0, 1), [1.0, 2.0], method="auto",
                      jac=lambda t, y: np.full((2, 2), np.nan))
    ok = pmd.solve_ivp(fun, (0, 1), [1.0, 2.0], method="auto", jac=lambda t, y: -np.eye(2))
    assert ok.success and ok.switched_to is None
    np.testing.assert_allclose(ok.y[:, -1], np.exp(-1) * np.array([1.0, 2.0]), rtol=3e-3)


# --------------------------------------------------------------------------------------------
# 4. A SphericalZYZ joint passing near its chart singularity: no success with a wrong answer.
# --------------------------------------------------------------------------------------------
def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rod_pair(q0, v0):
    """The same rod on SphericalZYZ (from q0, v0) and on Spherical (the same rotation and
    angular velocity: body rates = Rᵀ L(φ, θ) q̇, paper eq 38b)."""
    zyz = pmd.Model()
    zyz.add_body(rod_body(), pmd.SphericalZYZ(), parent=-1, name="rod")
    ball = pmd.Model()
    ball.add_body(rod_body(), pmd.Spherical(), parent=-1, name="rod")
    phi, th, psi = q0
    r = _rz(phi) @ _ry(th) @ _rz(psi)
    lmat = np.array([[0, -np.sin(phi), np.cos(phi) * np.sin(th)],
                     [0, np.cos(phi), np.sin(phi) * np.sin(th)], [1, 0, np.cos(th)]])
    w = 0.5 * np.sqrt(1 + np.trace(r))
    quat = [(r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w),
            (r[1, 0] - r[0, 1]) / (4 * w), w]
    return (pmd.Scene(zyz, q0, v0, effects=[pmd.Gravity(G)]),
            pmd.Scene(ball, quat, r.T @ lmat @ np.asarray(v0), effects=[pmd.Gravity(G)]))


@pytest.mark.parametrize("rtol", [1e-9, 1e-6])
def test_zyz_passing_near_its_singularity_fails_naming_it(rtol):
    zyz, ball = _rod_pair([0.3, 2e-3, 0.2], [0.5, -1.0, 0.3])
    r = pmd.simulate(zyz, (0, 1), rtol=rtol, atol=rtol * 1e-3)
    # On main: success, the rotation 2.4e-3 (rtol 1e-9) or 7.8e-4 (rtol 1e-6) off.
    assert not r.success and "Euler singularity" in r.message and "'rod'" in r.message
    assert 0 < r.t_reached < 1 and r.t[-1] == r.t_reached
    # What it kept is right: the same rotation as the quaternion joint's at that time.
    ref = pmd.simulate(ball, (0, r.t_reached), rtol=1e-12, atol=1e-14)
    got = zyz.model.placements(r.q[-1])[0][0]
    want = ball.model.placements(ref.q[-1])[0][0]
    assert np.abs(got - want).max() < 100 * rtol


def test_zyz_far_from_its_singularity_runs_to_the_end_accurately():
    zyz, ball = _rod_pair([0.3, 0.3, 0.2], [0.5, -1.0, 0.3])
    r = pmd.simulate(zyz, (0, 1), rtol=1e-9, atol=1e-12)
    ref = pmd.simulate(ball, (0, 1), rtol=1e-12, atol=1e-14)
    assert r.success
    got = zyz.model.placements(r.q[-1])[0][0]
    want = ball.model.placements(ref.q[-1])[0][0]
    assert np.abs(got - want).max() < 1e-7


# --------------------------------------------------------------------------------------------
# 19. simulate_batch: params of the wrong kind and threads=0 are input errors.
# --------------------------------------------------------------------------------------------
def test_simulate_batch_refuses_non_numeric_params_and_zero_threads():
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(InvalidInputError, match=r"params\['gravity'\]: expected numbers"):
        pmd.simulate_batch(scene, (0, 0.1), t_eval=[0, 0.1], params={"gravity": "x"})
    with pytest.raises(InvalidInputError, match="threads: expected a thread count >= 1"):
        pmd.simulate_batch(scene, (0, 0.1), t_eval=[0, 0.1], q0=np.tile(scene.q0, (2, 1)),
                           threads=0)


# --------------------------------------------------------------------------------------------
# Found by the extended fuzz: a driver or actuated index of another type.
# --------------------------------------------------------------------------------------------
def test_prescribed_motion_refuses_a_driver_of_another_type(fourbar_motion):
    scene, mo = fourbar_motion
    for driver in (np.inf, b"", 1.5, True):
        with pytest.raises(InvalidInputError, match="driver: expected a body name or an int"):
            pmd.prescribed_motion(scene.model, driver, speed=1.0, q_guess=scene.q0)
    with pytest.raises(InvalidInputError, match="actuated: expected"):
        pmd.analyze_motion(scene.model, mo.t, mo.q, mo.v, mo.a, actuated=[0.5])


# --------------------------------------------------------------------------------------------
# 3, 20. animate: a bounded frame count, and a missing directory said before any work.
# --------------------------------------------------------------------------------------------
def test_animate_bounds_the_frame_count_and_checks_the_directory(tmp_path, monkeypatch):
    from pointmass_dyn.viewer import _animation

    scene = pmd.load_scene("pendulum_planar")
    sol = pmd.simulate(scene, (0, 0.5))
    # Refused before any frame is sampled (not OOM-killed after minutes), whatever the clock.
    linspace = np.linspace

    def no_huge_linspace(start, stop, num=50, *args, **kwargs):
        assert num <= _animation.MAX_FRAMES, f"{num} frame times made before the refusal"
        return linspace(start, stop, num, *args, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(_animation.np, "linspace", no_huge_linspace)
        patch.setattr(_animation, "sample", lambda *a, **k: pytest.fail("a frame was sampled"))
        for kwargs in ({"fps": 1e9}, {"duration": 1e9}, {"frames": 10**9}):
            with pytest.raises(InvalidInputError, match="at most 108000"):
                pmd.animate(sol, scene, tmp_path / "x.html", **kwargs)
            assert not (tmp_path / "x.html").exists()
    with pytest.raises(InvalidInputError, match="path: expected a file in an existing dir"):
        pmd.animate(sol, scene, tmp_path / "missing" / "x.html")
    info = pmd.animate(sol, scene, tmp_path / "x.html", fps=20)
    assert info.frames == 10 and info.bytes > 0  # round(0.5 s × 20 fps), as before


# --------------------------------------------------------------------------------------------
# 25. RK4 (and Euler) refuse tolerances no method could use, as the adaptive ones do.
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["RK4", "Euler"])
def test_fixed_step_methods_refuse_bad_tolerances(method):
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(InvalidInputError, match="rtol"):
        pmd.simulate(scene, (0, 0.1), method=method, dt=1e-3, rtol=np.nan)
    with pytest.raises(InvalidInputError, match="atol"):
        pmd.simulate(scene, (0, 0.1), method=method, dt=1e-3, atol=-1)
    ok = pmd.simulate(scene, (0, 0.1), method=method, dt=1e-3)
    assert ok.success and np.all(np.isfinite(ok.q))


# --------------------------------------------------------------------------------------------
# 8, 16. balance / pareto_front weights and counts.
# --------------------------------------------------------------------------------------------
def test_balance_refuses_weights_and_counts_that_mean_nothing(fourbar_motion):
    _, mo = fourbar_motion
    cw = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.05, count=8)]
    for objective in ({"force": np.nan}, {"force": -1.0}, {"force": 0.0}, {"force": True}):
        with pytest.raises(InvalidInputError, match="objective"):
            pmd.balance(mo, counterweights=cw, objective=objective)
    # (`regularization` is gone with the conic solver: the least design mass decides ties.)
    for kwargs in ({"count": -1}, {"count": 1}, {"objectives": ("force", "moment", "torque")},
                   {"objectives": ("force", "force")}):
        with pytest.raises(InvalidInputError, match="count|objectives"):
            pmd.pareto_front(mo, counterweights=cw, **kwargs)


# --------------------------------------------------------------------------------------------
# 2. simulate_batch stopped by a raising progress or Ctrl-C: the exception carries every
#    run's result so far (finished runs whole, runs under way to where they stopped).
# --------------------------------------------------------------------------------------------
def _stoppable_batch_args():
    scene = pmd.load_scene("pendulum_planar")
    q0 = scene.q0 + np.linspace(0.0, 1.0, 400)[:, None]
    return scene, q0, {"t_span": (0, 50), "rtol": 1e-11, "atol": 1e-12, "threads": 2}


def _check_partial_batch(scene, q0, kw, batch):
    assert isinstance(batch, pmd.BatchResult) and len(batch) == len(q0)
    done = np.flatnonzero(batch.success)
    assert 0 < len(done) < len(q0)
    # A finished run is the simulate call it stands for (an independent single run).
    k = done[-1]
    single = pmd.Scene(scene.model, q0[k], scene.v0, scene.effects)
    ref = pmd.simulate(single, kw["t_span"], rtol=kw["rtol"], atol=kw["atol"])
    np.testing.assert_allclose(batch.results[k].q[-1], ref.q[-1], rtol=0, atol=1e-12)
    # Every other run says why it stopped and how far it got.
    for k in np.flatnonzero(~batch.success):
        r = batch.results[k]
        assert batch.status[k] == -1
        assert "interrupted" in r.message or "stopped before this run started" in r.message
        if len(r.t):
            assert r.t[-1] == pytest.approx(r.t_reached) and r.t_reached < 50


def test_simulate_batch_stopped_by_progress_keeps_every_run():
    scene, q0, kw = _stoppable_batch_args()
    seen = []

    def progress(done, total):
        seen.append(done)
        if done >= 3:
            raise RuntimeError("cancelled by the caller")

    with pytest.raises(RuntimeError, match="cancelled by the caller") as info:
        pmd.simulate_batch(scene, q0=q0, progress=progress, **kw)
    batch = info.value.result
    assert batch.success.sum() >= seen[-1]  # nothing finished is lost
    assert "in this exception's .result" in info.value.__notes__[-1]
    _check_partial_batch(scene, q0, kw, batch)


def test_simulate_batch_stopped_by_ctrl_c_keeps_every_run():
    # Pressed once a run is done, heard by the batch's own poll (tests/ctrl_c.py).
    from ctrl_c import CtrlC

    scene, q0, kw = _stoppable_batch_args()
    ctrl_c = CtrlC(inside="simulate_batch", armed=False)

    def progress(done, total):
        if done >= 1:
            ctrl_c.arm()

    error = ctrl_c.run(lambda: pmd.simulate_batch(scene, q0=q0, progress=progress, **kw))
    _check_partial_batch(scene, q0, kw, error.result)


# --------------------------------------------------------------------------------------------
# 6. simulate_batch of scenes of different sizes: each run's rows hold its own trajectory.
# --------------------------------------------------------------------------------------------
def test_simulate_batch_of_mixed_scenes_keeps_each_trajectory():
    pp, chain7 = pmd.load_scene("pendulum_planar"), pmd.load_scene("chain7")
    t_eval = [0.0, 0.25, 0.5]
    batch = pmd.simulate_batch([pp, chain7], (0, 0.5), t_eval=t_eval)
    assert batch.success.all() and batch.q.shape == (2, 3, 7) and batch.v.shape == (2, 3, 7)
    for k, scene in enumerate([pp, chain7]):
        ref = pmd.simulate(scene, (0, 0.5), t_eval=t_eval)
        nq, nv = scene.model.nq, scene.model.nv
        np.testing.assert_allclose(batch.q[k, :, :nq], ref.q, rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.v[k, :, :nv], ref.v, rtol=0, atol=1e-12)
        assert np.isnan(batch.q[k, :, nq:]).all() and np.isnan(batch.v[k, :, nv:]).all()


# --------------------------------------------------------------------------------------------
# params={"gravity": g} on a scene with two gravity effects: the bodies feel g, not 2 g.
# --------------------------------------------------------------------------------------------
def test_simulate_batch_gravity_param_is_the_total_gravity():
    pp = pmd.load_scene("pendulum_planar")
    half = pmd.Effect.gravity(0.5 * G)
    doubled = pp.replace(effects=[half, half])
    g = np.array([[0.0, 0.0, -3.0], [0.0, 0.0, -20.0]])
    batch = pmd.simulate_batch(doubled, (0, 0.5), t_eval=[0.5], params={"gravity": g})
    for k in range(2):
        ref = pmd.simulate(pp.replace(effects=[pmd.Effect.gravity(g[k])]), (0, 0.5),
                           t_eval=[0.5])
        np.testing.assert_allclose(batch.q[k], ref.q, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------------------------
# 23. Radau with atol = 0: refused naming atol (as RADAU5), not a failure at t = 0; rtol = 0
#     with atol > 0 runs (rtol raised to 100 ε, as SciPy) and is accurate.
# --------------------------------------------------------------------------------------------
def test_radau_refuses_zero_atol_and_runs_with_zero_rtol():
    pp = pmd.load_scene("pendulum_planar")
    for method in ("Radau", "auto"):
        for rtol, atol in ((0, 0), (1e-6, 0), (1e-6, [1e-8, 1e-8, 0, 1e-8, 1e-8, 1e-8])):
            with pytest.raises(InvalidInputError, match=r"atol: component \d must be > 0 .*got 0"):
                pmd.simulate(pp, (0, 1), method=method, rtol=rtol, atol=atol)
    r = pmd.simulate(pp, (0, 1), method="Radau", rtol=0, atol=1e-10)
    ref = pmd.simulate(pp, (0, 1), method="DOP853", rtol=1e-13, atol=1e-13)
    assert r.success
    np.testing.assert_allclose(r.q[-1], ref.q[-1], rtol=0, atol=1e-7)


# --------------------------------------------------------------------------------------------
# 24. Radau names the cause: a NaN from fun (and when), a NaN from jac, Newton failing.
# --------------------------------------------------------------------------------------------
def test_radau_names_nan_from_fun_nan_from_jac_and_newton():
    def fun(t, y):  # harmonic oscillator, NaN from t = 0.5 on
        return np.array([y[1], -y[0] if t < 0.5 else np.nan])

    r = pmd.solve_ivp(fun, (0, 1), [1.0, 0.0], method="Radau")
    assert not r.success and "right-hand side returned a non-finite value" in r.message
    assert 0.49 < r.t_reached <= 0.5 and "step size" not in r.message
    np.testing.assert_allclose(r.y[:, -1], [np.cos(r.t_reached), -np.sin(r.t_reached)],
                               atol=1e-3)

    def jac(t, y):
        return np.array([[0.0, 1.0], [-1.0, np.nan if t > 0.5 else 0.0]])

    r = pmd.solve_ivp(lambda t, y: np.array([y[1], -y[0]]), (0, 1), [1.0, 0.0],
                      method="Radau", jac=jac)
    assert not r.success and "the Jacobian returned a non-finite value" in r.message
    assert r.t_reached > 0.5
    # f = 1e20 sin y with a zero Jacobian: Newton contracts only for h below ~1e-20, under
    # the minimum step 10 ulp(1) = 2.2e-15 of a run starting at t = 1.
    r = pmd.solve_ivp(lambda t, y: 1e20 * np.sin(y), (1, 2), [1.0], method="Radau",
                      jac=np.zeros((1, 1)))
    assert not r.success and "Newton iteration did not converge" in r.message
    assert r.t_reached == 1.0


# --------------------------------------------------------------------------------------------
# Round 2, viewer: mesh files with non-finite vertices, a FIFO, a name with a NUL, a shape
# beyond float32. Each is drawn as far as it can be (or as its inertia box) with one
# VisualWarning naming it; never a ValueError from the camera, a hang, or NaN in the page.
# --------------------------------------------------------------------------------------------
def _binary_stl(path, triangles):
    import struct

    with open(path, "wb") as fh:
        fh.write(b" " * 80 + struct.pack("<I", len(triangles)))
        for t in triangles:
            fh.write(struct.pack("<12fH", 0, 0, 1, *np.ravel(t), 0))


def test_animate_survives_broken_visuals(tmp_path, monkeypatch):
    import os
    import pickle
    import warnings

    from pointmass_dyn.errors import VisualWarning
    from pointmass_dyn.viewer import _meshes as viewer_meshes

    monkeypatch.setenv("PMD_MESH_CACHE", "0")
    viewer_meshes._read_cached.cache_clear()
    good = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]])
    _binary_stl(tmp_path / "nan.stl", [good, good + np.nan])
    os.mkfifo(tmp_path / "fifo.stl")
    scene = pmd.load_scene("pendulum_planar")
    eye = np.eye(3).tolist()

    def mesh(path):
        return {"body": 0, "kind": "mesh", "rotation": eye, "translation": [0, 0, 0],
                "uri": path, "path": path, "scale": [1, 1, 1], "rgba": None}

    model = pickle.loads(pickle.dumps(scene.model))
    model.set_visuals([
        mesh(str(tmp_path / "nan.stl")),
        mesh(str(tmp_path / "fifo.stl")),
        mesh(str(tmp_path / "a\x00b.stl")),
        {"body": 0, "kind": "box", "size": [1e308] * 3, "rotation": eye,
         "translation": [0, 0, 0], "rgba": None},
    ])
    vs = viewer_meshes.visual_scene(model, warn=False)
    # The one finite triangle of nan.stl is kept, exactly (float32 of the file's values).
    drawn = [m for m in vs.meshes if len(m.faces) == 1]
    assert len(drawn) == 1
    np.testing.assert_array_equal(np.sort(drawn[0].vertices, axis=0),
                                  np.sort(good.astype(np.float32), axis=0))
    assert all(np.isfinite(m.vertices).all() for m in vs.meshes)
    assert set(vs.failed) == {str(tmp_path / "fifo.stl"), str(tmp_path / "a\x00b.stl"),
                              "box of body 'rod'"}
    sol = pmd.simulate(scene, (0, 0.2))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pmd.animate(sol, pmd.Scene(model, scene.q0, scene.v0, scene.effects),
                    tmp_path / "x.html")
    msgs = [str(w.message) for w in caught if issubclass(w.category, VisualWarning)]
    assert len(msgs) == 1 and "3 mesh file(s) or shape(s)" in msgs[0]
    assert "not a regular file" in msgs[0] and "beyond float32" in msgs[0]
    page = (tmp_path / "x.html").read_text()
    assert "NaN" not in page and "Infinity" not in page


# --------------------------------------------------------------------------------------------
# Round 2, CLI: an output in a missing directory, a --trail body the model does not have,
# a bad --size are refused before the run (they were found after it, the run lost).
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("argv, named", [
    (["simulate", "pendulum_planar", "--out", "{d}/missing/x.csv"], "--out"),
    (["simulate", "pendulum_planar", "--plot", "{d}/missing/x.png"], "--plot"),
    (["simulate", "pendulum_planar", "--animate", "{d}/x.html", "--trail", "nobody"], "--trail"),
    (["simulate", "pendulum_planar", "--animate", "{d}/x.gif", "--size", "big"], "--size"),
    (["animate", "pendulum_planar", "--out", "{d}/missing/x.html"], "--out"),
    (["sweep", "pendulum_planar", "--runs", "2", "--q0-noise", "0.1",
      "--out", "{d}/missing/x.npz"], "--out"),
])
def test_cli_refuses_bad_outputs_before_running(argv, named, tmp_path, monkeypatch, capsys):
    from pointmass_dyn import cli
    from pointmass_dyn.cli import _animate, _simulate, _sweep

    def no_run(*args, **kwargs):
        raise AssertionError("the run started before the arguments were checked")

    for module, name in ((_simulate, "simulate"), (_animate, "simulate"),
                         (_sweep, "simulate_batch")):
        monkeypatch.setattr(module, name, no_run)
    assert cli.main([a.format(d=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert f"error: {named}: expected" in err


# --------------------------------------------------------------------------------------------
# Round 2: a batch whose results alone exceed the machine's memory is refused at once with
# OutOfMemoryError (10^8 runs built 10^8 scenes in Python, then ran out of memory).
# --------------------------------------------------------------------------------------------
def test_simulate_batch_beyond_memory_is_refused_up_front(monkeypatch):
    from pointmass_dyn import _batch
    from pointmass_dyn.errors import OutOfMemoryError

    scene = pmd.load_scene("pendulum_planar")
    # A machine of 1 GiB: 10^6 runs need 4.4 GB (the bound measured per run).
    monkeypatch.setattr(_batch, "_physical_memory", lambda: 2**30)
    with pytest.raises(OutOfMemoryError, match=r"1000000 runs need at least 4\.1 GiB"):
        pmd.simulate_batch(scene, (0, 0.1), params={"rod.mass": np.ones(10**6)})
    with pytest.raises(OutOfMemoryError, match=r"1000 runs .* 10000 output times of 6"):
        pmd.simulate_batch(scene, (0, 0.1), q0=np.tile(scene.q0, (1000, 1)),
                           t_eval=np.linspace(0, 0.1, 10**4))
    monkeypatch.undo()
    ok = pmd.simulate_batch(scene, (0, 0.1), q0=np.tile(scene.q0, (3, 1)))
    assert ok.success.all()


# --------------------------------------------------------------------------------------------
# Round 2, loops: max_iterations < 1 is our error (a builtin OverflowError for -1).
# --------------------------------------------------------------------------------------------
def test_assemble_refuses_iteration_counts_below_one():
    scene = pmd.load_scene("fourbar")
    for bad in (-1, 0, True, 10**30):
        with pytest.raises(InvalidInputError, match="max_iterations: expected a whole number"):
            scene.model.assemble(scene.q0, max_iterations=bad)
    q = scene.model.assemble(scene.q0 + 0.05, fixed=[0])
    assert np.abs(scene.model.constraint_residual(q)).max() < 1e-12
    assert q[0] == scene.q0[0] + 0.05


# --------------------------------------------------------------------------------------------
# Round 2 (found by the fuzz): assemble_velocity of a guess near the largest double gave
# [-inf, -inf, inf] without a word.
# --------------------------------------------------------------------------------------------
def test_assemble_velocity_overflow_is_a_numerical_error():
    from pointmass_dyn.errors import NumericalError

    scene = pmd.load_scene("fourbar")
    model = scene.model
    with pytest.raises(NumericalError, match="assemble_velocity: the result is not finite"):
        model.assemble_velocity(scene.q0, np.full(model.nv, 1e308))
    # Linear in the guess: 1e200 × the projection of ones, to rounding.
    unit = model.assemble_velocity(scene.q0, np.ones(model.nv))
    big = model.assemble_velocity(scene.q0, np.full(model.nv, 1e200))
    np.testing.assert_allclose(big / 1e200, unit, rtol=1e-12)
    assert np.abs(model.constraint_jacobian(scene.q0) @ unit).max() < 1e-12
