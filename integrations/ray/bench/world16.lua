-- big.lua's forest (same species, density and tiles of 250 m) over 4 km x 4 km: 16 km², 256
-- tiles, about 1.7 million trees. The world of bench/world16.sh.
local p = pge.params{
  points = {3000, min = 100, max = 20000, doc = "attraction points per tree"},
  variants = {8, min = 1, max = 64, doc = "meshes grown per species"},
}

local species = "../../../scripts/species/"
local forest = pge.Forest{ size = {4000, 4000}, seed = 7, tile = 250 }
forest:terrain{ height = 40, scale = 400, octaves = 5 }
forest:scatter{ species = species .. "oak.lua", minDistance = 9, altitude = {-100, 0},
                variants = p.variants, params = { points = p.points } }
forest:scatter{ species = species .. "conifer.lua", minDistance = 2.7, altitude = {-5, 100},
                slope = {0, 35}, variants = p.variants }
forest:scatter{ species = species .. "bush.lua", minDistance = 2.2, density = 0.8,
                variants = p.variants, scale = {0.5, 1.0}, params = { points = 400 } }
return forest
