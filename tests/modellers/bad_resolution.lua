local meta = pge.Metaballs()
meta:addParticle({0, 0, 0}, 1)
local mc = pge.MarchingCubes(meta, { resolution = 0 })
return mc
