"""A plugin held in the tests: a tree, ``glider_survey``, for a vehicle kind of its own, ``glider`` (tests/test_plugin_declaration.py).

The test installs it as pip would (a ``gliderplugin-1.0.dist-info`` naming ``gliderplugin.trees:build`` in the
``executive.trees`` entry-point group); nothing of the executive names it.
"""
