"""The figures' shared look."""

COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")
"""Colour cycle: the first controller (or the pulse train) blue, the second orange, a
limit or best-so-far line red."""
