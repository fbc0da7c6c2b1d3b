"""Former module path (the flat layout before the subpackages) of the GIF/MP4 writer, kept so that
code importing it keeps working; the names live in :mod:`pointmass_dyn.viewer`."""

from .viewer import (
    figure,
    write_video,
)

__all__ = [
    "figure",
    "write_video",
]
