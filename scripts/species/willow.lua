-- A weeping willow: the points lie only in a thick dome-shaped shell that reaches almost to
-- the ground; a straight trunk grows up the empty middle to the top of the dome, and the
-- long thin branches spread from there over the shell and, pulled by a strong downward
-- tropism, hang down its outside. Fibrous bark, many small, light, narrow leaves.
local p = pge.params{
  points = {3500, min = 100, max = 200000, doc = "attraction points"},
  droop = {0.6, min = 0, max = 0.95, doc = "downward tropism"},
}

local outer = pge.shape.ellipsoid{ center = {0, 4.0, 0}, radii = {5.0, 5.5, 5.0} }
local inner = pge.shape.ellipsoid{ center = {0, 4.0, 0}, radii = {3.8, 4.3, 3.8} }
local ground = pge.shape.box{ min = {-7, -2, -7}, max = {7, 0.8, 7} }

return pge.SpaceColonization{
  envelope = pge.shape.difference{ pge.shape.difference{ outer, inner }, ground },
  points = p.points,
  step = 0.25, influence = 2.2, kill = 0.5,
  trunk = 6.2,
  tropism = {0, -p.droop, 0},
  radius = { tip = 0.014, exponent = 2.1 },
  smoothing = 0.3,
  mesh = { sides = 8, mergeStraight = 4, color = "#6a5a48", bark = "fibrous", flare = { roots = 4, spread = 0.6 } },
  leaves = { perTip = {4, 6}, size = 0.1, perCard = 12, maxDepth = 4, along = { spacing = 0.25 }, colors = {"#7f9f3a", "#b5c95a"},
             shape = "lanceolate", backColor = "#d2dcbe", translucency = 0.35 },
}
