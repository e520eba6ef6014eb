"""cloudcore: the cloudview engine.

Model, shading, LOD policy and statistics are plain numpy; only the `gl`
sub-package touches OpenGL.
"""
