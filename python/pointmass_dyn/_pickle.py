"""Pickling and copies of the extension's classes, registered with :mod:`copyreg` (whose
dispatch table ``pickle``, ``copy.copy`` and ``copy.deepcopy`` all consult).

``_core._dumps(obj)`` gives ``(data, callables)``: ``data`` is a versioned, checksummed
binary encoding of the whole object (every float bit for bit, derived data included) and
``callables`` the Python functions of its ``TorqueFunction`` effects, in order, which pickle
stores by reference like any function. :func:`_load` (a module-level function, so pickle
finds it by name in any process) rebuilds the object; data that is damaged or from another
format version raises :class:`pointmass_dyn.errors.UnpicklingError`.
"""

from __future__ import annotations

import copyreg

from . import _core

#: Every class of the extension whose instances a user can hold.
PICKLED_CLASSES = (
    _core.DenseSolution,
    _core.Effect,
    _core.Joint,
    _core.Model,
    _core.PointMasses,
    _core.RigidBody,
    _core.Scene,
    _core.StateEvent,
)


def _load(data: bytes, callables: tuple = ()):
    """Rebuilds an object from ``_core._dumps``'s ``(data, callables)``."""
    return _core._loads(data, callables)


def _reduce(obj):
    data, callables = _core._dumps(obj)
    return _load, (data, callables)


for _cls in PICKLED_CLASSES:
    copyreg.pickle(_cls, _reduce)
