"""What comes in from and goes out to other tools' files: OpenVDB density grids, heightmaps, camera paths."""
