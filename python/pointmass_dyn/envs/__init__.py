"""Scenes as Gymnasium environments (optional extra ``gym``): :class:`SceneEnv` and the
threaded :class:`VectorSceneEnv` (docs/control.md)."""

from ._env import SceneEnv, VectorSceneEnv

__all__ = ["SceneEnv", "VectorSceneEnv"]
