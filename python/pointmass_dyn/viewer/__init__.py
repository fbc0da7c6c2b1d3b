"""Animations of results (docs/visualisation.md): a self-contained WebGL page (``.html``), a
GIF or an MP4 (matplotlib), or a live Meshcat view, all drawn from one :class:`Drawing`.

    pmd.animate(result, scene, "run.html", trails=["rod"], shaking=True)
    pmd.show_meshcat(result, scene)                  # the optional extra ``meshcat``

:func:`prepare` gives the :class:`Drawing` without writing it; :func:`project` maps world
points to the page's pixels at a frame's camera (what the tests check the page against).
A model's visual geometry (``Model.visuals``: URDF ``<visual>``, MJCF geoms) is drawn as
triangles (:func:`visual_scene`; mesh files need the extra ``pointmass-dyn[mesh]``).
"""

from ._animation import AnimationInfo, animate, frame_times, has_contact, prepare, sample
from ._drawing import (
    BOX_EDGES,
    COLOURS,
    CONTACT_SHARE,
    LAYERS,
    TRAIL_COLOURS,
    VIEWS,
    Drawing,
    box_corners,
    build_drawing,
    camera_at,
    default_camera,
    project,
    view_projection,
)
from ._html import page, write_html
from ._meshcat import show
from ._meshes import inertia_box, visual_scene
from ._video import contact_segments, figure, write_video

__all__ = [
    "BOX_EDGES",
    "COLOURS",
    "CONTACT_SHARE",
    "LAYERS",
    "TRAIL_COLOURS",
    "VIEWS",
    "AnimationInfo",
    "Drawing",
    "animate",
    "box_corners",
    "build_drawing",
    "camera_at",
    "contact_segments",
    "default_camera",
    "figure",
    "frame_times",
    "has_contact",
    "inertia_box",
    "page",
    "prepare",
    "project",
    "sample",
    "show",
    "view_projection",
    "visual_scene",
    "write_html",
    "write_video",
]
