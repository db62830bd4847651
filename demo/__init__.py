"""The reference application as commands: the pick-and-place demo and its evaluation.

This is the top layer: it wires the engine, the robot's actors, the missions and the
simulator together (nothing imports it).
"""
