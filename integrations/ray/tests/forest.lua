-- The Ray tests' (and tests/merge.rs') forest: 80 m x 80 m cut into 16 tiles of 20 m, two
-- species, two variants each.
-- `spin` makes every pge run of it slower (a busy loop), so a test can kill a worker in the
-- middle of a tile; `broken` adds a species that fails when a tile grows it (not when
-- `pge tiles` lists the tiles).
local p = pge.params{
  spin = {0, min = 0, max = 1e9, doc = "iterations of a busy loop before the forest"},
  broken = {false, doc = "add a species that fails to grow"},
}

local n = 0
for k = 1, p.spin do n = n + k % 3 end

local forest = pge.Forest{ size = {80, 80}, seed = 3, tile = 20 }
forest:terrain{ height = 3, scale = 60, octaves = 2 }
forest:scatter{ species = "shrub.lua", minDistance = 4, variants = 2, scale = {0.8, 1.2} }
forest:scatter{ species = function(params, seed)
                  return pge.SpaceColonization{
                    envelope = pge.shape.ellipsoid{ center = {0, 0.5, 0}, radii = {0.4, 0.4, 0.4} },
                    points = 25, step = 0.12, influence = 0.6, kill = 0.2, roots = {{0, 0, 0}},
                    mesh = { sides = 3, color = "#6e5b3b" } }
                end, minDistance = 3, variants = 2, density = 0.5 }
if p.broken then
  forest:scatter{ species = function() error("no sap in this species") end, minDistance = 6 }
end
return forest
