"""Animations of results (docs/visualisation.md): a self-contained WebGL page (``.html``), a
GIF or an MP4 (matplotlib), or a live Meshcat view, all drawn from one :class:`Drawing`.

    pmd.animate(result, scene, "run.html", trails=["rod"], shaking=True)
    pmd.show_meshcat(result, scene)                  # the optional extra ``meshcat``

:func:`prepare` gives the :class:`Drawing` without writing it; :func:`project` maps world
points to the page's pixels at the initial camera (what the tests check the page against).
"""

from ._animation import AnimationInfo, animate, frame_times, prepare, sample
from ._drawing import (
    BOX_EDGES,
    COLOURS,
    TRAIL_COLOURS,
    VIEWS,
    Drawing,
    box_corners,
    build_drawing,
    default_camera,
    project,
    view_projection,
)
from ._html import page, write_html
from ._meshcat import show
from ._video import figure, write_video

__all__ = [
    "BOX_EDGES",
    "COLOURS",
    "TRAIL_COLOURS",
    "VIEWS",
    "AnimationInfo",
    "Drawing",
    "animate",
    "box_corners",
    "build_drawing",
    "default_camera",
    "figure",
    "frame_times",
    "page",
    "prepare",
    "project",
    "sample",
    "show",
    "view_projection",
    "write_html",
    "write_video",
]
