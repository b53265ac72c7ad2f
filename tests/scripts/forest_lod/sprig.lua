-- A sprig for the forest LOD tests, smaller than the shrub: a few dozen leaves; `lod = 1`
-- gives it its own levels of detail.
local p = pge.params{
  points = {60, min = 10, max = 1000, doc = "attraction points"},
  lod = {0, min = 0, max = 1, doc = "1: the shrub's own levels of detail"},
}
return pge.SpaceColonization{
  envelope = pge.shape.ellipsoid{ center = {0, 0.8, 0}, radii = {0.6, 0.5, 0.6} },
  points = p.points, step = 0.15, influence = 0.8, kill = 0.25, roots = {{0, 0, 0}},
  mesh = { sides = 4, color = "#5e4b3b" },
  leaves = { perTip = {2, 4}, size = 0.2, maxDepth = 2, colors = {"#3d6b25"} },
  lod = p.lod == 1 and {} or nil,
}
