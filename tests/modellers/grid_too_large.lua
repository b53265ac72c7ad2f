-- One particle whose reach covers the whole grid: at this resolution the per-block lists
-- alone need more than the session's memory limit (run with --memory-limit 16).
local meta = pge.Metaballs{ radius = 10 }
meta:addParticle({0, 0, 0}, 1)
local mc = pge.MarchingCubes(meta, { resolution = 1200 })
local model = mc:model()
return model
