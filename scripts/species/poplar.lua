-- A columnar (Lombardy) poplar: a tall, narrow capsule crown and upward tropism, so every
-- branch climbs close to the trunk. Smooth grey-brown bark with horizontal lenticels.
local p = pge.params{
  points = {4000, min = 100, max = 200000, doc = "attraction points in the crown"},
  height = {14, min = 4, max = 40, doc = "tree height (m)"},
  width = {1.6, min = 0.3, max = 6, doc = "crown radius (m)"},
}

return pge.SpaceColonization{
  envelope = pge.shape.capsule{ a = {0, 2.5 + p.width, 0}, b = {0, p.height - p.width, 0}, radius = p.width },
  points = p.points,
  step = 0.25, influence = 1.6, kill = 0.45,
  tropism = {0, 0.6, 0},
  radius = { tip = 0.018, exponent = 2.5 },
  mesh = { sides = 7, mergeStraight = 4, color = "#7d7465", bark = "smooth" },
  leaves = { perTip = {4, 6}, size = 0.07, perCard = 12, maxDepth = 4, along = { spacing = 0.1 }, colors = {"#4f7d2a", "#8fae3e"},
             backColor = "#dce6c8", translucency = 0.3 },
}
