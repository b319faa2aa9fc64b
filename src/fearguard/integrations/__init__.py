"""Adapters for the loops users already drive in: ``donkey`` (a Donkey Car part), ``gym`` (a gymnasium shield).

Each module converts the host's units and sign conventions explicitly at its boundary; neither is
imported by ``import fearguard`` (the car pays only for what it uses).
"""
