-- The forest of forest.lua without a camera: its shrubs' levels of detail come from the
-- species (`own = 1`) or from the forest's own `lod` (`own = 0`), and no instance has a count.
local p = pge.params{
  own = {1, min = 0, max = 1, doc = "1: the species asks for lod, 0: the forest does"},
}
local forest = pge.Forest{ size = {60, 40}, seed = 9, tile = 20,
                           lod = p.own == 0 and { sectors = 1 } or nil }
forest:terrain{ height = 2, scale = 40, octaves = 2 }
forest:scatter{ species = "shrub.lua", minDistance = 4, density = 0.5, variants = 3,
                params = { lod = p.own } }
forest:scatter{ species = "sprig.lua", minDistance = 3, variants = 2,
                params = { lod = p.own, points = 30 } }
return forest
