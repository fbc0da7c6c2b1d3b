"""Shared model builders for the core test suite.

Everything here builds *inputs* (bodies, trees, states) and independent references
(Pinocchio models built from the same description); no expected output of pointmass_dyn is
ever hard-coded.
"""

from __future__ import annotations

import atexit
import math
import os
import shutil
import tempfile
from dataclasses import dataclass, field

import numpy as np
import pointmass_dyn as pmd
import pytest

# Simplified robot meshes are cached on disk (pmd.viewer): in a directory of this run, not
# the user's ~/.cache.
_MESH_CACHE = tempfile.mkdtemp(prefix="pmd-mesh-cache-")
os.environ.setdefault("PMD_MESH_CACHE", _MESH_CACHE)
atexit.register(shutil.rmtree, _MESH_CACHE, True)

G = np.array([0.0, 0.0, -9.81])

# --------------------------------------------------------------------------------------------
# Worst errors seen, printed at the end of the run (for the report; not asserted here).
# --------------------------------------------------------------------------------------------
WORST: dict[str, float] = {}


def record(name: str, value: float) -> float:
    """Remembers the largest `value` seen under `name`; returns `value`."""
    value = float(value)
    if not (value <= WORST.get(name, -math.inf)):
        WORST[name] = value
    return value


def pytest_sessionfinish(session):
    # Under pytest-xdist each worker sends its worst errors to the controller.
    if hasattr(session.config, "workeroutput"):
        session.config.workeroutput["worst_relative_errors"] = dict(WORST)


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    for name, value in getattr(node, "workeroutput", {}).get("worst_relative_errors", {}).items():
        record(name, value)


def pytest_terminal_summary(terminalreporter):
    if WORST:
        terminalreporter.section("worst relative errors seen")
        for k in sorted(WORST):
            terminalreporter.write_line(f"{k:70s} {WORST[k]:.3e}")


def rel_err(got, ref) -> float:
    """max|got − ref| / max|ref| (absolute if the reference is zero)."""
    got = np.asarray(got, dtype=float)
    ref = np.asarray(ref, dtype=float)
    assert got.shape == ref.shape, (got.shape, ref.shape)
    scale = np.max(np.abs(ref)) if ref.size else 0.0
    err = np.max(np.abs(got - ref)) if ref.size else 0.0
    return float(err / scale) if scale > 0 else float(err)


# --------------------------------------------------------------------------------------------
# Bodies
# --------------------------------------------------------------------------------------------
PAPER_M, PAPER_A, PAPER_D = 2.51, 1.0, 0.02


def assert_finite(what: str, value) -> None:
    """Every float in a result (arrays, tuples, dicts, results) is finite: the fuzz
    contract (tests/test_fuzz_api.py), no NaN or inf unless an exception says why."""
    if isinstance(value, (bool, int, str, type(None))):
        return
    if isinstance(value, float):
        assert math.isfinite(value), f"{what}: {value}"
    elif isinstance(value, np.ndarray):
        if value.dtype.kind == "f":
            assert np.all(np.isfinite(value)), f"{what}: non-finite entries"
    elif isinstance(value, (tuple, list)):
        for k, v in enumerate(value):
            assert_finite(f"{what}[{k}]", v)
    elif isinstance(value, dict):
        for k, v in value.items():
            assert_finite(f"{what}[{k!r}]", v)
    elif isinstance(value, pmd.SimulationResult):
        for name in ("t", "q", "v", "energy"):
            assert_finite(f"{what}.{name}", getattr(value, name))


def rod_inertia(m: float, a: float, d: float) -> np.ndarray:
    """Solid cylinder of length a, diameter d, axis x, about its COM."""
    return np.diag(
        [m * d * d / 8, m * d * d / 16 + m * a * a / 12, m * d * d / 16 + m * a * a / 12]
    )


def rod_body(m: float = PAPER_M, a: float = PAPER_A, d: float = PAPER_D) -> pmd.RigidBody:
    """The paper's rod: body frame at one end, x along the rod."""
    return pmd.RigidBody(m, [a / 2, 0.0, 0.0], rod_inertia(m, a, d))


def revolute_chain(n: int) -> pmd.Model:
    """n revolute rods (1 kg, 0.3 m) in series, axes alternating y and z."""
    m = pmd.Model()
    parent = -1
    for k in range(n):
        axis = [0, 1, 0] if k % 2 == 0 else [0, 0, 1]
        parent = m.add_body(
            rod_body(1.0, 0.3, 0.02),
            pmd.Revolute(axis),
            parent=parent,
            translation=[0.3 if k else 0.0, 0, 0],
        )
    return m


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Uniform random rotation (from a normalised Gaussian quaternion)."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    return quat_to_matrix(q)


def quat_to_matrix(q) -> np.ndarray:
    """Rotation matrix of a unit quaternion (x, y, z, w), scalar last (SciPy / Pinocchio)."""
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def inertia_from_second_moments(mass: float, sigma, rotation) -> np.ndarray:
    """Inertia about the COM of a body whose principal second moments Σ m x² are `sigma`
    (any non-negative numbers: this is exactly the set of physical inertias, triangle
    inequality included), rotated by `rotation`."""
    s1, s2, s3 = sigma
    d = np.diag([s2 + s3, s1 + s3, s1 + s2])
    r = np.asarray(rotation)
    i = r @ d @ r.T
    return 0.5 * (i + i.T)


def random_body(
    rng: np.random.Generator, mass_range=(0.2, 5.0), size=(0.05, 0.6), com_scale=0.3
) -> pmd.RigidBody:
    """A well-shaped random body (moderate aspect ratio), for the dynamics tests."""
    m = rng.uniform(*mass_range)
    ext = rng.uniform(*size, size=3)
    sigma = m * ext**2 / 3.0
    inertia = inertia_from_second_moments(m, sigma, random_rotation(rng))
    com = rng.uniform(-com_scale, com_scale, size=3)
    return pmd.RigidBody(m, com, inertia)


def random_unit_quat(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


# --------------------------------------------------------------------------------------------
# Trees: one description, built both in pointmass_dyn and in Pinocchio
# --------------------------------------------------------------------------------------------
KINDS = ("Revolute", "Prismatic", "Spherical", "SphericalZYZ", "Fixed")


@dataclass
class BodySpec:
    body: pmd.RigidBody
    kind: str
    parent: int
    rotation: np.ndarray
    translation: np.ndarray
    axis: np.ndarray | None = None
    point_mass_center: np.ndarray | None = None


@dataclass
class TreeSpec:
    bodies: list[BodySpec] = field(default_factory=list)

    def kinds(self):
        return [b.kind for b in self.bodies]


def make_joint(spec: BodySpec) -> pmd.Joint:
    if spec.kind == "Revolute":
        return pmd.Revolute(spec.axis)
    if spec.kind == "Prismatic":
        return pmd.Prismatic(spec.axis)
    if spec.kind == "Spherical":
        return pmd.Spherical()
    if spec.kind == "SphericalZYZ":
        return pmd.SphericalZYZ()
    if spec.kind == "Fixed":
        return pmd.Fixed()
    if spec.kind == "FreeFlyer":
        return pmd.FreeFlyer()
    raise AssertionError(spec.kind)


def build_model(tree: TreeSpec, centers: bool = True) -> pmd.Model:
    """The tree as a pointmass_dyn model; `centers=False` ignores the point-mass centres."""
    model = pmd.Model()
    for k, b in enumerate(tree.bodies):
        kw = {}
        if centers and b.point_mass_center is not None:
            kw["point_mass_center"] = b.point_mass_center
        idx = model.add_body(
            b.body,
            make_joint(b),
            parent=b.parent,
            translation=b.translation,
            rotation=b.rotation,
            name=f"b{k}",
            **kw,
        )
        assert idx == k
    return model


def build_pinocchio(tree: TreeSpec, gravity=None):
    """The same tree in Pinocchio.

    SphericalZYZ → revolute Z, Y, Z at the same placement with two massless bodies between;
    Spherical → JointModelSpherical; FreeFlyer → JointModelFreeFlyer (the same convention); Revolute/Prismatic with arbitrary axes → the Unaligned
    joints; Fixed → the body's inertia appended to the joint that carries its parent.
    Returns (model, data)."""
    import pinocchio as pin

    pm = pin.Model()
    pm.gravity.linear = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)
    # For each of our bodies: the Pinocchio joint carrying it and its frame in that joint's frame.
    carrier: list[tuple[int, pin.SE3]] = []
    for k, b in enumerate(tree.bodies):
        if b.parent < 0:
            parent_joint, parent_frame = 0, pin.SE3.Identity()
        else:
            parent_joint, parent_frame = carrier[b.parent]
        placement = parent_frame * pin.SE3(
            np.asarray(b.rotation, float), np.asarray(b.translation, float)
        )
        inertia = pin.Inertia(b.body.mass, np.asarray(b.body.com), np.asarray(b.body.inertia))
        if b.kind == "Fixed":
            pm.appendBodyToJoint(parent_joint, inertia, placement)
            carrier.append((parent_joint, placement))
            continue
        if b.kind == "Revolute":
            jid = pm.addJoint(
                parent_joint,
                pin.JointModelRevoluteUnaligned(np.asarray(b.axis, float) / np.linalg.norm(b.axis)),
                placement,
                f"j{k}",
            )
        elif b.kind == "Prismatic":
            jid = pm.addJoint(
                parent_joint,
                pin.JointModelPrismaticUnaligned(
                    np.asarray(b.axis, float) / np.linalg.norm(b.axis)
                ),
                placement,
                f"j{k}",
            )
        elif b.kind == "Spherical":
            jid = pm.addJoint(parent_joint, pin.JointModelSpherical(), placement, f"j{k}")
        elif b.kind == "FreeFlyer":
            jid = pm.addJoint(parent_joint, pin.JointModelFreeFlyer(), placement, f"j{k}")
        elif b.kind == "SphericalZYZ":
            j1 = pm.addJoint(parent_joint, pin.JointModelRZ(), placement, f"j{k}_z1")
            pm.appendBodyToJoint(j1, pin.Inertia.Zero(), pin.SE3.Identity())
            j2 = pm.addJoint(j1, pin.JointModelRY(), pin.SE3.Identity(), f"j{k}_y")
            pm.appendBodyToJoint(j2, pin.Inertia.Zero(), pin.SE3.Identity())
            jid = pm.addJoint(j2, pin.JointModelRZ(), pin.SE3.Identity(), f"j{k}_z2")
        else:
            raise AssertionError(b.kind)
        pm.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        carrier.append((jid, pin.SE3.Identity()))
    return pm, pm.createData()


def random_tree(
    seed: int,
    n: int = 12,
    kinds=KINDS,
    centers: bool = False,
    require_all: bool = True,
    dfs: bool = True,
) -> TreeSpec:
    """A random tree of `n` bodies, parents drawn among earlier bodies (or the world),
    random placements, random joint axes. Every kind in `kinds` appears at least once when
    `require_all`. The first body always moves (so a root Fixed does not weld everything).
    `dfs=True` adds the bodies in depth-first order: Pinocchio's CRBA silently returns a wrong
    mass matrix for trees whose joints are not in depth-first order (its subtree velocity
    ranges assume it), while RNEA and ABA do not care."""
    rng = np.random.default_rng(seed)
    order = list(kinds) if require_all else []
    while len(order) < n:
        order.append(kinds[rng.integers(len(kinds))])
    head = [k for k in order if k != "Fixed"]
    rest = [k for k in order if k == "Fixed"]
    first = head.pop(rng.integers(len(head))) if head else order.pop()
    tail = head + rest
    rng.shuffle(tail)
    order = [first] + tail
    tree = TreeSpec()
    for k, kind in enumerate(order):
        if k == 0:
            parent = -1
        elif dfs:
            # Depth-first order (what Pinocchio's CRBA assumes): the parent is the last body
            # added or one of its ancestors, or the world.
            path = [k - 1]
            while tree.bodies[path[-1]].parent >= 0:
                path.append(tree.bodies[path[-1]].parent)
            if rng.random() < 0.1:
                parent = -1
            else:
                parent = int(path[min(int(rng.geometric(0.5)) - 1, len(path) - 1)])
        else:
            parent = int(rng.integers(-1, k)) if rng.random() < 0.15 else int(rng.integers(0, k))
        axis = None
        if kind in ("Revolute", "Prismatic"):
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
        center = rng.uniform(-0.5, 0.5, size=3) if centers else None
        tree.bodies.append(
            BodySpec(
                body=random_body(rng),
                kind=kind,
                parent=parent,
                rotation=random_rotation(rng),
                translation=rng.uniform(-0.5, 0.5, size=3),
                axis=axis,
                point_mass_center=center,
            )
        )
    return tree


def moving_kinds(model: pmd.Model) -> list[str]:
    """Joint kinds of the moving links, in q/v order (bodies are added in order and every
    non-Fixed body defines a link)."""
    kinds = [model.body_info(i)[1] for i in range(model.nbodies)]
    kinds = [k for k in kinds if k != "Fixed"]
    assert len(kinds) == model.nlinks
    return kinds


def random_state(model: pmd.Model, rng: np.random.Generator, vscale: float = 1.0):
    """Random (q, v) for a model: unit quaternions, ZYZ θ kept away from 0 and π."""
    q = np.empty(model.nq)
    link_kinds = moving_kinds(model)
    for kind, (iq, _, _, _) in zip(link_kinds, model.joint_slices()):
        if kind == "Spherical":
            q[iq : iq + 4] = random_unit_quat(rng)
        elif kind == "FreeFlyer":
            q[iq : iq + 3] = rng.uniform(-0.5, 0.5, size=3)
            q[iq + 3 : iq + 7] = random_unit_quat(rng)
        elif kind == "SphericalZYZ":
            q[iq : iq + 3] = [
                rng.uniform(-np.pi, np.pi),
                rng.uniform(0.4, np.pi - 0.4),
                rng.uniform(-np.pi, np.pi),
            ]
        elif kind == "Prismatic":
            q[iq] = rng.uniform(-0.5, 0.5)
        else:
            q[iq] = rng.uniform(-np.pi, np.pi)
    v = rng.normal(size=model.nv) * vscale
    return q, v


def normalize_q(model: pmd.Model, q: np.ndarray) -> np.ndarray:
    """Renormalises the quaternions of q."""
    q = np.array(q, dtype=float)
    for kind, (iq, _, _, _) in zip(moving_kinds(model), model.joint_slices()):
        if kind == "Spherical":
            q[iq : iq + 4] /= np.linalg.norm(q[iq : iq + 4])
        elif kind == "FreeFlyer":
            q[iq + 3 : iq + 7] /= np.linalg.norm(q[iq + 3 : iq + 7])
    return q


def paper_pendulum_tree() -> TreeSpec:
    """The paper's spatial solid pendulum: the rod on a ZYZ spherical joint at the origin."""
    return TreeSpec([BodySpec(rod_body(), "SphericalZYZ", -1, np.eye(3), np.zeros(3))])


# Keep Hypothesis' example database and patch files out of the repository.
def _hypothesis_home():
    import tempfile

    from hypothesis import configuration, settings

    configuration.set_hypothesis_home_dir(
        os.path.join(tempfile.gettempdir(), "pointmass_dyn_hypothesis")
    )
    settings.register_profile("pointmass_dyn", database=None, deadline=None)
    settings.load_profile("pointmass_dyn")


_hypothesis_home()


def pytest_report_header(config):
    # Which build the suite tests: the installed wheel or the source tree, and which copy of
    # the multiversioned loops (POINTMASS_DYN_BASELINE=1 forces the portable one).
    return f"pointmass_dyn {pmd.__version__} from {os.path.dirname(pmd.__file__)}, " \
        f"CPU dispatch: {pmd._core.cpu_dispatch}"


# Floating-base robots of example-robot-data (two humanoids, two quadrupeds), loaded both
# ways: ours with root_joint="free", Pinocchio's with JointModelFreeFlyer.
FLOATING = {
    "talos": "talos_data/robots/talos_full_v2.urdf",
    "g1": "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "a1": "a1_description/urdf/a1.urdf",
}


def robots_dir():
    """example-robot-data's robots folder (pmd.robots), or None if it is not installed."""
    try:
        return pmd.robots.directory()
    except pmd.errors.InvalidInputError:
        return None


@pytest.fixture(scope="module", params=sorted(FLOATING))
def floating_robot(request):
    """(name, our model, Pinocchio's model with gravity (0, 0, -9.81)), joint names equal;
    mimic joints independent in both (Pinocchio's default)."""
    import warnings

    import pinocchio as pin

    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    path = str(root / FLOATING[request.param])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
        model = pmd.Model.from_urdf(path, root_joint="free", mimic=False)
    pm = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
    pm.gravity.linear = np.array([0.0, 0.0, -9.81])
    assert model.joint_names == list(pm.names)[1:]
    return request.param, model, pm



@pytest.fixture(scope="session")
def design_page_run(tmp_path_factory):
    """docs/design.md's python blocks run once for the whole session, in order in one
    namespace, in a scratch directory (tests/test_docs.py's way: its ``blocks`` and markers),
    every ``balance`` recorded (fronts' points included) and ``balance``'s own warnings (a
    written part off the design, a least-mass stage that failed) raised as errors. Returns
    ``(motion, Balance)`` of each design made. tests/test_docs.py and
    tests/test_design_connected.py share it (the page takes ~18 s)."""
    import warnings

    from pointmass_dyn.design import _front
    from test_docs import REQUIREMENTS, ROOT, blocks

    pytest.importorskip("matplotlib").use("Agg")  # blocks that plot write files only
    page = ROOT / "docs" / "design.md"
    made = []
    real = pmd.balance

    def recording(*args, **kwargs):
        made.append((args[0], real(*args, **kwargs)))
        return made[-1][1]

    mp = pytest.MonkeyPatch()
    mp.setattr(pmd, "balance", recording)
    mp.setattr(_front, "balance", recording)
    mp.chdir(tmp_path_factory.mktemp("design-page"))
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("error", message="balance:", category=RuntimeWarning)
            namespace: dict = {"__name__": "docs.design"}
            for line, marker, code in blocks(page):
                if marker == "not run" or (marker and not all(
                        REQUIREMENTS[r.strip()]() for r in marker.split(":", 1)[1].split(","))):
                    continue
                where = f"{page.relative_to(ROOT)}:{line}"
                try:
                    exec(compile(code, where, "exec"), namespace)
                except Exception as e:
                    raise AssertionError(f"the python block at {where} fails: {e!r}") from e
    finally:
        mp.undo()
    return made
