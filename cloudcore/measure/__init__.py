"""Measurement: frame statistics, overdraw, heat maps, image comparison, benchmarks, recordings,
overlays, screenshot checks."""
