"""Foxglove: a run served live, and the layout shipped with the package."""
