"""The frame's particles: the particle buffer (the clouds' particles lit, carried by the wind, weighed by a cloud
field's blend weights: `buffer`), a draw's batch of them far to near (`batch`, sorted by `depth_order`), and
which of them can be drawn as point sprites (`point_sprites`).  Plain numpy; `cloudcore.gl` draws them."""
