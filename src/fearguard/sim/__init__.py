"""Scenario simulator: scenario files, a road/traffic world, a camera renderer, sensors and metrics.

``scenario`` (files) → ``world`` (road, bicycle model, traffic, ``render``, ``sensors``) → ``metrics``.
The closed loop that drives a World with the supervisor lives in ``sim.loop``.
"""
