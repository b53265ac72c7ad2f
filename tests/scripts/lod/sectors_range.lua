-- sectors outside 1..=64.
return pge.turtle{ leaves = {}, lod = { sectors = 65 } }
