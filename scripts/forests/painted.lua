-- A forest painted by hand: density.png is a greyscale map stretched over the world (white
-- grows trees, black keeps a clearing); the terrain is fBm.
local p = pge.params{
  points = {1000, min = 100, max = 20000, doc = "attraction points per tree"},
}

local forest = pge.Forest{ size = {200, 200} }
forest:terrain{ height = 12, scale = 180 }
forest:scatter{ species = "../species/oak.lua", minDistance = 8, density = "density.png",
                variants = 3, params = { points = p.points } }
-- Bushes at the edge of the clearing, from a density function.
forest:scatter{ species = "../species/bush.lua", minDistance = 3, variants = 2,
                density = function(x, z)
                  local r = math.sqrt(x * x + z * z)
                  return (r > 30 and r < 55) and 0.6 or 0
                end,
                params = { points = 300 } }
return forest
