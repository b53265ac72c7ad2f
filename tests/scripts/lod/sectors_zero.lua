-- sectors = 0 is outside 1..=64.
return pge.turtle{ leaves = {}, lod = { sectors = 0 } }
