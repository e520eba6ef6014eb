"""The world around the clouds: the camera and how it moves, the sun, the terrain, opaque objects and the
wind (numpy, float64)."""
