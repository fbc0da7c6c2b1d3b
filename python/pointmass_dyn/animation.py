"""Former module path (the flat layout before the subpackages) of the animation entry point,
sampling, the drawing and the camera, kept so that code importing it keeps working; the names
live in :mod:`pointmass_dyn.viewer`."""

from .viewer import (
    COLOURS,
    TRAIL_COLOURS,
    VIEWS,
    AnimationInfo,
    Drawing,
    animate,
    build_drawing,
    default_camera,
    frame_times,
    prepare,
    project,
    sample,
    view_projection,
)

__all__ = [
    "COLOURS",
    "TRAIL_COLOURS",
    "VIEWS",
    "AnimationInfo",
    "Drawing",
    "animate",
    "build_drawing",
    "default_camera",
    "frame_times",
    "prepare",
    "project",
    "sample",
    "view_projection",
]
