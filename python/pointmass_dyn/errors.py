"""The package's exceptions. Every message names the argument (or file and key), what was
expected and what was given."""

from __future__ import annotations

import pickle


class PointMassDynError(Exception):
    """Base of every error raised by pointmass_dyn."""


class InvalidInputError(PointMassDynError, ValueError):
    """An argument of the wrong shape, type or range, or a non-finite number."""


class ArgumentTypeError(InvalidInputError, TypeError):
    """An argument of the wrong Python type altogether (a float for a count, an int for a
    method name): also a ``TypeError``."""


class InertiaError(InvalidInputError):
    """A mass, centre of mass or inertia tensor no rigid body can have."""


class ModelStructureError(InvalidInputError):
    """A kinematic tree that cannot be built: unknown parent, duplicate name."""


class LoopClosureError(InvalidInputError):
    """A closed kinematic loop that cannot be closed from the given configuration (the bodies
    cannot reach, or held coordinates ask for a position the mechanism cannot take); the
    message names the loop."""


class InfeasibleDesignError(InvalidInputError):
    """A design (``pmd.balance``) whose limits or zero quantities no design within the bounds
    meets. ``relaxation``: for each limit and zero quantity, ``(asked, needed)`` in the
    problem's norm — the least summed relaxation (each relative to its value before) some
    design meets; ``binding``: the names relaxed there beyond the solver's tolerance;
    ``alone``: the least value of each when only it is relaxed, the others held (None when
    that does not suffice)."""

    def __init__(
        self,
        message: str,
        relaxation: dict | None = None,
        binding: tuple = (),
        alone: dict | None = None,
    ):
        super().__init__(message)
        self.relaxation = dict(relaxation or {})
        self.binding = tuple(binding)
        self.alone = dict(alone or {})

    def __reduce__(self):
        return (type(self), (str(self), self.relaxation, self.binding, self.alone))


class NumericalError(PointMassDynError, ArithmeticError):
    """Finite inputs gave a non-finite or meaningless result (overflow, singular matrix)."""


class SingularityError(NumericalError):
    """The equations cannot be solved at this state (e.g. a ZYZ joint at sin(theta) = 0)."""


class OutOfMemoryError(PointMassDynError, MemoryError):
    """A computation whose arrays (sized by the model) the system cannot provide; the message
    names the computation and the size. Raised before the computation starts."""


class SimulationError(PointMassDynError, RuntimeError):
    """A simulation that could not finish; ``t`` is the time it reached and ``result`` what
    was computed up to there (a ``SimulationResult``), when there is one."""

    def __init__(self, message: str, t: float | None = None, result=None):
        super().__init__(message)
        self.t = t
        self.result = result

    def __reduce__(self):
        return (type(self), (str(self), self.t, self.result))


class SceneError(InvalidInputError):
    """A scene file or scene description that cannot be loaded; names the file and the key."""


class UrdfError(InvalidInputError):
    """A URDF file that cannot be loaded; names the file and the element (joint or link)."""


class UnpicklingError(PointMassDynError, pickle.UnpicklingError):
    """Pickled data that cannot be loaded: not ours, truncated or altered (a checksum guards
    it), or written by a version of pointmass_dyn with another serialisation format."""


class AnimationWriterError(PointMassDynError, RuntimeError):
    """An animation format this machine cannot write (MP4 without ffmpeg, video without
    matplotlib or Pillow); the message says what to install or which format works instead."""


class ClusterError(PointMassDynError, ConnectionError):
    """A Dask scheduler that did not answer within the stated timeout (``sweep``'s
    ``connect_timeout``); the message names the address."""


class UrdfWarning(UserWarning):
    """A URDF loaded differently from what it says (mimic joints, ignored elements)."""


class UrdfRepairWarning(UrdfWarning):
    """Inertials changed by ``Model.from_urdf(..., repair=...)``: one warning per load,
    listing each link (before → after); ``model.repairs`` holds the same records."""


class VisualWarning(UserWarning):
    """Visual geometry an animation could not draw as the model says (a mesh file missing,
    unreadable or too large, the mesh readers not installed): one warning per animation,
    naming the files; those bodies are drawn with simple shapes."""


class ModelImportWarning(UserWarning):
    """A model imported from MuJoCo or Pinocchio differs from its source in something that
    does not enter the mass matrix or bias forces (equality constraints, limits, ...)."""


class SingularPassageWarning(UserWarning):
    """A run of a mechanism with loops ended a step at a singular position (within
    rounding): past it the motion may continue on another branch, chosen by rounding
    (``SimulationResult.singular_passage`` holds the time; docs/mechanisms.md §5)."""


__all__ = [
    "AnimationWriterError",
    "ClusterError",
    "InertiaError",
    "InfeasibleDesignError",
    "InvalidInputError",
    "LoopClosureError",
    "ModelStructureError",
    "NumericalError",
    "OutOfMemoryError",
    "PointMassDynError",
    "SceneError",
    "SimulationError",
    "SingularityError",
    "SingularPassageWarning",
    "UnpicklingError",
    "UrdfError",
    "UrdfWarning",
    "UrdfRepairWarning",
    "ModelImportWarning",
    "VisualWarning",
]
