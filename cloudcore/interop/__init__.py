"""Clouds in and out of the files other tools keep volumes in: OpenVDB density grids."""
