-- A tiled forest whose shrubs and sprigs have levels of detail, and each tree's leaves for
-- a camera standing at the forest's edge: a budget of `total` leaves for the whole forest.
local p = pge.params{
  total = {3000, min = 0, max = 1000000, doc = "leaves the whole forest may draw"},
  own = {1, min = 0, max = 1, doc = "1: the species asks for lod, 0: the forest does"},
}
local forest = pge.Forest{ size = {60, 40}, seed = 9, tile = 20,
                           lod = { camera = {-30, 2, -5}, total = p.total, near = 4, far = 45 } }
forest:terrain{ height = 2, scale = 40, octaves = 2 }
forest:scatter{ species = "shrub.lua", minDistance = 4, density = 0.5, variants = 3,
                params = { lod = p.own } }
forest:scatter{ species = "sprig.lua", minDistance = 3, variants = 2,
                params = { lod = p.own, points = 30 } }
return forest
