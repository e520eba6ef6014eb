"""Light: the sun and sky, Harris's light pass, the eye pass, phase functions, the splat kernel,
and the path-traced truth."""
