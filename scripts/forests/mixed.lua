-- A mixed temperate forest: oaks and poplars in the valleys, conifers on the slopes above
-- them. Three species scripts from the library, each grown in a few variants and instanced.
local p = pge.params{
  size = {300, min = 50, max = 4000, doc = "side of the world (m)"},
  points = {1200, min = 100, max = 20000, doc = "attraction points per tree"},
  variants = {4, min = 1, max = 32, doc = "meshes grown per species"},
}

local forest = pge.Forest{ size = {p.size, p.size}, tile = 100 }
forest:terrain{ height = 30, scale = 250, octaves = 5 }

-- Broadleaves below 4 m, where the valleys are.
forest:scatter{ species = "../species/oak.lua", minDistance = 11, altitude = {-100, 4},
                slope = {0, 25}, variants = p.variants, scale = {0.8, 1.2},
                params = { points = p.points } }
forest:scatter{ species = "../species/poplar.lua", minDistance = 6, density = 0.5,
                altitude = {-100, 6}, variants = p.variants, scale = {0.9, 1.1},
                params = { points = p.points } }
-- Conifers above 2 m on slopes up to 40 degrees.
forest:scatter{ species = "../species/conifer.lua", minDistance = 5, altitude = {2, 100},
                slope = {0, 40}, variants = p.variants, scale = {0.7, 1.3} }
return forest
