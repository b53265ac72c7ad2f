-- A bush: five stems from the ground into a low, wide crown.
local p = pge.params{
  points = {1800, min = 100, max = 100000, doc = "attraction points"},
  stems = {5, min = 1, max = 12, doc = "stems from the ground"},
}

local roots = {}
for i = 1, p.stems do
  local a = 2 * math.pi * i / p.stems
  roots[i] = {0.35 * math.cos(a), 0, 0.35 * math.sin(a)}
end

return pge.SpaceColonization{
  envelope = pge.shape.ellipsoid{ center = {0, 1.0, 0}, radii = {2.2, 1.1, 2.0} },
  points = p.points,
  step = 0.12, influence = 0.9, kill = 0.22,
  roots = roots,
  tropism = {0, 0.1, 0},
  radius = { tip = 0.01, exponent = 2.3 },
  mesh = { sides = 5, mergeStraight = 5, color = "#7a7266", bark = "smooth" },
  leaves = { perTip = {3, 5}, size = 0.05, perCard = 12, maxDepth = 2, along = { spacing = 0.08 }, colors = {"#3d6b25", "#6e9a35"} },
}
