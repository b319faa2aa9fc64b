"""Driving: one loop for every world (``loop.run``), the world and controller protocols, runs as data (a plan of
rows, ``run_row``, ``merge``) and the one suite; signal handling for the frame loops (``interrupt``).
"""
