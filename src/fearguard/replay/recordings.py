"""Open any recording ``fearguard replay`` reads: a video, an image folder, a Donkey tub (sources.py) or a ROS bag (bags.py).

Its own module so that sources.py, which bags.py builds on, need not know about bags.
"""

from __future__ import annotations

from pathlib import Path

from fearguard.readings import finite_reading
from fearguard.replay.bags import BagSource, BagTopics, is_bag
from fearguard.replay.sources import FrameSource, SourceError, open_source


def open_recording(path: str | Path, fps: float | None = None, topics: BagTopics | None = None) -> FrameSource:
    """A ROS bag (a ``.bag``, a ROS 2 bag folder or its ``metadata.yaml``, a ``.db3`` or ``.mcap`` file) as a ``BagSource``
    reading ``topics``; anything else through ``open_source``."""
    path = Path(path)
    if path.is_file() and path.name == "metadata.yaml":
        path = path.parent  # a ROS 2 bag's metadata was given: open the bag
    if path.exists() and is_bag(path):
        if fps is not None and not ((finite_reading(fps) or 0.0) > 0):
            raise SourceError(path, "fps", f"must be a positive number of frames per second, got {fps!r}")
        return BagSource(path, fps, topics)
    return open_source(path, fps)
