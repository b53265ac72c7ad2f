-- A small shrub for the Ray tests: few attraction points, so a tile grows in a moment.
local p = pge.params{
  points = {60, min = 10, max = 1000, doc = "attraction points"},
}

return pge.SpaceColonization{
  envelope = pge.shape.ellipsoid{ center = {0, 0.8, 0}, radii = {0.8, 0.6, 0.8} },
  points = p.points,
  step = 0.15, influence = 0.8, kill = 0.25,
  roots = {{0, 0, 0}},
  radius = { tip = 0.01, exponent = 2.3 },
  mesh = { sides = 4, color = "#5e4b3b" },
  leaves = { perTip = {1, 2}, size = 0.15, maxDepth = 1, colors = {"#3d6b25"} },
}
