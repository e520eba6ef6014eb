"""Small maths shared by the engine: vectors, noise, colour, ramps, segmented arrays, keyframed paths, the
splat kernel and the depth-aware upsampling of a reduced pass (numpy, float64)."""
