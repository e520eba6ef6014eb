"""Cloud fields to the horizon (Yusov 2014, section 5.2): the camera-centred nested grid, a cell's particles,
the step that makes only the cells entering a ring."""
