"""The level of detail: the frame plan, units of interpenetrating clouds, the cost model, impostors,
Wang's ring, layers around objects, depth order."""
