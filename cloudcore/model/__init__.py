"""The scene model: immutable records (the scene, its clouds, the renderer's settings), the one error type
for bad input, and the low-level readers of its files (typed TOML tables, particle arrays).  It imports no
feature."""
