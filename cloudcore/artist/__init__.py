"""Wang's artist tools: the sprite atlas, artist shading, particle styles, facing locks, formation and
dissipation, cloud presets."""
