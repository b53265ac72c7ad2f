-- One skeleton, two methods: an L-system draws the trunk and four main limbs, then space
-- colonization fills a crown from the limbs' tips. pge.tree meshes the joined skeleton
-- with one bark and one set of leaves: smooth grey bark and palmate leaves, like a maple.
local p = pge.params{
  points = {2500, min = 100, max = 50000, doc = "attraction points in the crown"},
}

local limbs = pge.LSystem("limbs")
limbs:createInstance(function() return pge.turtle{ angle = 38, step = 1, width = 0.2 } end)
limbs:axiom("F(2.2) A")
limbs:rule("A -> [&F(1.6)] /(90) [&F(1.5)] /(90) [&F(1.7)] /(90) [&F(1.4)] F(1.2)")
limbs:iterations(1)

local trunk = limbs:algorithm():skeleton()

local crown = pge.SpaceColonization{
  start = trunk,
  envelope = pge.shape.ellipsoid{ center = {0, 4.6, 0}, radii = {3.2, 2.4, 3.2} },
  points = p.points,
  step = 0.18, influence = 1.4, kill = 0.35,
}

return pge.tree{
  skeleton = crown:skeleton(),
  radius = { tip = 0.015, exponent = 2.4 },
  mesh = { sides = 7, color = "#8a8478", bark = "smooth" },
  leaves = { perTip = {3, 5}, size = 0.12, perCard = 12, maxDepth = 2, along = { spacing = 0.3 }, colors = {"#2f6b1f", "#7da83a"}, shape = "palmate",
             backColor = "#dcd26e", translucency = 0.4 },
}
