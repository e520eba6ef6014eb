"""A physically based atmosphere (Hillaire 2020, "A Scalable and Production Ready Sky and Atmosphere Rendering
Technique"; its reference implementation sebh/UnrealEngineSkyAtmosphere): the air's parameters, its medium,
the ray/planet geometry, the transmittance, multiple-scattering and sky-view tables, and what the renderer
asks of them (sky radiance, the sun's transmitted light, the sky's irradiance).  numpy, float64, metres;
radiances per unit of solar irradiance at the top of the atmosphere.  docs/atmosphere.md.
"""
