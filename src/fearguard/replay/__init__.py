"""Replay recorded drives through the supervisor: frame sources (video, image folder, Donkey tub) and sensor logs."""
