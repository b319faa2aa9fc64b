"""fearguard in MetaDrive: the road car's camera preset, the simulator as a world, drives, metrics and a suite.

``preset`` and ``metrics`` are plain Python; ``headless``, ``world`` and ``drive`` import MetaDrive only when a world
is opened (``bash .ci/metadrive.sh`` builds the environment that has it).

    from fearguard.worlds.metadrive import DriveOptions, drive
    result = drive(DriveOptions(map_blocks="SCSC", traffic_density=0.05, seconds=30), "out/md")
"""
