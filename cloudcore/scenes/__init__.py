"""Scenes coming in and changed: scene files loaded and saved, what the renderer can draw checked, the
artist's edits, and clouds, heightmaps and camera paths from and to other tools' files."""
