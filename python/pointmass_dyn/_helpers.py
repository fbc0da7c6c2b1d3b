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


def float_array(arg: str, x, expected: str = "an array of real numbers") -> np.ndarray:
    """``x`` as a float array, or an :class:`InvalidInputError` naming ``arg`` (not NumPy's
    ValueError for a string or TypeError for an object it cannot read)."""
    try:
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(
            f"{arg}: expected {expected}, got {type(x).__name__} {x!r:.60}"
        ) from exc


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


def attach_partial(error: BaseException, result, note: str) -> BaseException:
    """Attaches what a stopped computation had done (``result``) to the exception that
    stopped it as ``.result``, with ``note`` in its traceback (``__notes__``); an exception
    type that takes no attributes is left as it is."""
    try:
        error.result = result
        notes = getattr(error, "__notes__", None)
        if notes is None:
            error.__notes__ = [note]
        else:
            notes.append(note)
    except (AttributeError, TypeError):
        pass
    return error


def stop_reason(error: BaseException) -> str:
    """Why a computation stopped, for a partial result's ``message``: Ctrl-C or a
    ``progress`` callback raising ``KeyboardInterrupt`` read as an interrupt, anything else
    as the exception's type and text."""
    if isinstance(error, KeyboardInterrupt):
        return "interrupted (Ctrl-C, or KeyboardInterrupt raised by progress)"
    text = str(error)
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


#: The run settings' defaults in the signatures of ``simulate`` and ``simulate_batch``: left
#: at these, a keyword says nothing (a ``RunConfig``, the scene or the core's default decide).
_SETTING_DEFAULTS = {"energy": False, "power": False, "controller": "standard", "stiffness": "warn"}


def changed_settings(**settings) -> dict:
    """The run settings a call states, as ``RunConfig``'s keywords: those not ``None`` and
    not at their signature's default."""
    return {
        k: v
        for k, v in settings.items()
        if v is not None and not (k in _SETTING_DEFAULTS and v == _SETTING_DEFAULTS[k])
    }
