"""Learning the track: a profile of the car's own recordings (``fearguard learn``, ``track/learn.py``) and the
familiarity cue it gives (``profile.py``, ``reading.py``)."""

from fearguard.track.profile import TrackProfile, load_track, save_track

__all__ = ["TrackProfile", "load_track", "save_track"]
