"""The process: the garbage collector kept off the frame, the on-disk cache of slow work."""
