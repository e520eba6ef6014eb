"""What a frame drew and what it cost, per frame: its statistics, the overdraw, the heat map, the plan's
outlines for the editor (numpy)."""
