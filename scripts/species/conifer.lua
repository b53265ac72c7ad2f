-- A conifer (spruce): a cone envelope and a straight leader grown first through the whole
-- crown (strong apical growth); the points along it pull the leader's nodes into side
-- branches, longest at the bottom, which droop a little, stay their course and carry sprays
-- of dark needles.
-- Plated bark, like a pine's.
local p = pge.params{
  points = {3500, min = 100, max = 200000, doc = "attraction points"},
  height = {12, min = 3, max = 40, doc = "tree height (m)"},
  radius = {3.2, min = 0.5, max = 10, doc = "crown radius at the base (m)"},
}

local base = 1.5
local crown = pge.shape.cone{ base = {0, base, 0}, apex = {0, p.height, 0}, radius = p.radius }

return pge.SpaceColonization{
  envelope = crown,
  points = p.points,
  step = 0.22, influence = 1.3, kill = 0.35,
  trunk = p.height - base - 0.5,
  tropism = {0, -0.3, 0},
  -- Side branches hold their course: a tip keeps half its direction, sees only the points
  -- ahead of it, and never turns more than 100 degrees from where it started, so the lower
  -- branches do not follow the cone up and back toward the leader.
  persistence = 0.5, perception = 90, maxTurn = 100,
  radius = { tip = 0.015, exponent = 2.6 },
  mesh = { sides = 7, mergeStraight = 5, color = "#5a4032", bark = "plated" },
  leaves = { perTip = {6, 9}, size = 0.4, width = 0.8, maxDepth = 3, colors = {"#163b22", "#2c5a30"},
             shape = "needles", backColor = "#8caa78", translucency = 0.1 },
}
