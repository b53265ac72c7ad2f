-- Foliage levels of detail: the oak of scripts/species/oak.lua with `lod`, so its leaf mesh
-- is written in the order of the vector V with a LOD table in extras.pge.lod (any level is
-- two ranges of the index buffer), and collapsed leaves textured from an atlas of clusters.
local p = pge.params{
  points = {3000, min = 100, max = 200000, doc = "attraction points in the crown"},
  leaves = {9, min = 1, max = 40, doc = "most leaves per branch tip"},
  lod = {1, min = 0, max = 1, doc = "1: levels of detail, 0: plain leaves"},
  sectors = {1, min = 1, max = 64, doc = "angular sectors simplified apart"},
  atlas = {1, min = 0, max = 1, doc = "1: texture collapsed leaves from a cluster atlas"},
}

return pge.SpaceColonization{
  envelope = pge.shape.ellipsoid{ center = {0, 6.4, 0}, radii = {5.5, 3.2, 5} },
  points = p.points,
  step = 0.3, influence = 2.4, kill = 0.6,
  tropism = {0, 0.05, 0},
  radius = { tip = 0.025, exponent = 2.2 },
  smoothing = 0.5,
  mesh = { sides = 8, mergeStraight = 6, color = "#5a4636" },
  leaves = { perTip = {math.max(1, p.leaves - 3), p.leaves}, size = 0.38, maxDepth = 3,
             colors = {"#2c5418", "#4e7a26"} },
  lod = p.lod == 1 and { sectors = math.floor(p.sectors), atlas = p.atlas == 1 } or nil,
}
