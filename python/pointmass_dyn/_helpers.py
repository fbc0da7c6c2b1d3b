"""Small helpers that several parts of the package share (one definition each): RMS and peak
magnitudes, matplotlib's pyplot on demand, rotation matrices of quaternions, the gravity a
scene feels, where a model's quaternions sit in q, and sample counts checked before allocating."""

from __future__ import annotations

import operator

import numpy as np

from .errors import InvalidInputError


def rms(x) -> float:
    """RMS of the magnitude of the rows of x (N, k), or of x (N,); 0 for no rows."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return 0.0
    sq = x**2 if x.ndim == 1 else np.sum(x**2, axis=-1)
    return float(np.sqrt(np.mean(sq)))


def peak(x) -> float:
    """Largest magnitude of the rows of x (N, k), or of x (N,); 0 for no rows."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return 0.0
    return float(np.max(np.abs(x) if x.ndim == 1 else np.linalg.norm(x, axis=-1)))


def pyplot(needed_for: str = "plots", error: type[Exception] = ImportError, instead: str = ""):
    """``matplotlib.pyplot`` on the Agg backend (unless one is already chosen), imported only
    when a plot is asked for; without matplotlib, ``error`` naming the extra to install."""
    try:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise error(
            f"{needed_for} need matplotlib: pip install 'pointmass-dyn[plot]'"
            + (f" ({instead})" if instead else "")
        ) from exc
    return plt


def rotation_of_wxyz(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions (..., 4) in (w, x, y, z) order (MuJoCo's),
    normalised first."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def scene_gravity(scene) -> np.ndarray | None:
    """The gravity a scene's bodies feel: the sum of its gravity effects, None when it has
    none or its ``disable`` switches the family off (as the simulation applies them)."""
    if "gravity" in (scene.disable or ()):
        return None
    gs = [np.asarray(e.g, dtype=float) for e in scene.effects if e.g is not None]
    return np.sum(gs, axis=0) if gs else None


def quaternion_slices(model) -> list[slice]:
    """The q entries that hold unit quaternions (x, y, z, w): a quaternion spherical joint's
    q, a free flyer's last four."""
    out = []
    for iq, _iv, nq, nv in model.joint_slices():
        if nq == nv + 1:  # Spherical (q = xyzw) or FreeFlyer (q = xyz, xyzw)
            out.append(slice(iq + nq - 4, iq + nq))
    return out


def sample_count(name: str, value, lowest: int = 1, largest: int = 10_000_000) -> int:
    """``value`` as a whole number of samples in [lowest, largest], or our error naming ``name``.

    The upper bound keeps a mistyped count (a float where an int was meant) from allocating
    gigabytes before anything can fail.
    """
    try:
        count = operator.index(value)
    except TypeError:
        if isinstance(value, float) and value.is_integer():
            count = int(value)
        else:
            raise InvalidInputError(
                f"{name}: expected a whole number of samples, got {value!r}"
            ) from None
    if not lowest <= count <= largest:
        raise InvalidInputError(
            f"{name}: expected a number of samples in [{lowest}, {largest:,}], got {count:,}"
        )
    return count
