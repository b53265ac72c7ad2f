-- A plantation: conifers in rows on seed 000's jittered grid over gently rolling ground,
-- with a few bushes between the rows.
local p = pge.params{
  spacing = {4, min = 1, max = 50, doc = "minimum distance between trunks (m)"},
  points = {300, min = 100, max = 20000, doc = "attraction points per bush"},
}

local forest = pge.Forest{ size = {120, 80}, tile = 40 }
forest:terrain{ height = 4, scale = 200, octaves = 3 }
forest:scatter{ species = "../species/conifer.lua", method = "jittered", jitter = 0.1,
                minDistance = p.spacing, variants = 3, scale = {0.9, 1.1},
                params = { height = 9, radius = 1.8 } }
forest:scatter{ species = "../species/bush.lua", minDistance = 2, density = 0.3,
                variants = 2, scale = {0.6, 1.0}, params = { points = p.points } }
return forest
