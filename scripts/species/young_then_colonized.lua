-- One skeleton, two methods: a young tree grown by nutrient transport for 30 feedings,
-- then space colonization grows it on into a wide crown envelope, as an older tree fills
-- the space it is given.
local p = pge.params{
  feedings = {30, min = 1, max = 200, doc = "feedings of the young tree"},
  points = {3000, min = 100, max = 50000, doc = "attraction points in the crown"},
}

local young = pge.Growth{ steps = p.feedings, scale = 0.45, girth = 0.35 }

return pge.SpaceColonization{
  start = young:skeleton(),
  envelope = pge.shape.ellipsoid{ center = {0, 5.5, 0}, radii = {4, 2.8, 4} },
  points = p.points,
  step = 0.2, influence = 1.6, kill = 0.4,
  radius = { tip = 0.015, exponent = 2.3 },
  mesh = { sides = 7, color = "#6b5444" },
  leaves = { perTip = {3, 6}, size = 0.08, perCard = 12, maxDepth = 2, along = { spacing = 0.15 }, colors = {"#356b22", "#86a83a"} },
}
