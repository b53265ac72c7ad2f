-- A broad oak: a wide, flattened ellipsoid crown on a short, thick trunk flaring into its
-- roots, deeply furrowed bark, dark lobed leaves.
local p = pge.params{
  points = {3000, min = 100, max = 200000, doc = "attraction points in the crown"},
  width = {5.5, min = 1, max = 20, doc = "crown half-width (m)"},
  height = {3.2, min = 1, max = 20, doc = "crown half-height (m)"},
  leaves = {9, min = 0, max = 40, doc = "most leaves per branch tip"},
}

return pge.SpaceColonization{
  envelope = pge.shape.ellipsoid{ center = {0, 3.2 + p.height, 0}, radii = {p.width, p.height, p.width * 0.9} },
  points = p.points,
  step = 0.3, influence = 2.4, kill = 0.6,
  tropism = {0, 0.05, 0},
  radius = { tip = 0.025, exponent = 2.2 },
  smoothing = 0.5,
  mesh = { sides = 10, mergeStraight = 6, color = "#5a4636",
           bark = { style = "furrowed", depth = 1.3 }, flare = { roots = 5, spread = 0.9 } },
  leaves = { perTip = {math.max(0, p.leaves - 3), p.leaves}, size = 0.1, perCard = 12, maxDepth = 3,
             along = { orders = 2, spacing = 0.15 },
             colors = {"#2c5418", "#4e7a26"}, shape = "lobed",
             backColor = "#b4c86e", translucency = 0.25 },
}
