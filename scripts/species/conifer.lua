-- A pine, grown by pge.Conifer (an excurrent tree): a straight leader that adds one
-- internode and one whorl of 3 to 5 branches a year, each whorl turned from the one below;
-- an open, round-topped crown (ogive) whose lower branches have been shed, the branches
-- rising near the top and levelling out toward the base, bare near the trunk, with flat
-- sprays of shoots carrying long needles at their ends. Plated bark.
-- One step is one year: `--steps 8` is the sapling, `--stages 6,12,22` three ages.
local p = pge.params{
  height = {12, min = 3, max = 40, doc = "tree height after `years` years (m)"},
  radius = {3.2, min = 0.5, max = 10, doc = "crown radius: the longest branch (m)"},
  years = {22, min = 1, max = 200, doc = "years of growth: one internode and one whorl a year"},
}

return pge.Conifer{
  years = p.years, height = p.height, crownRadius = p.radius,
  crown = "ogive", crownBase = 0.3,
  perWhorl = {3, 5}, angle = {45, 85}, droop = 16, jitter = 0.25, waviness = 0.03,
  segment = 0.25, orders = 2, bare = 0.35,
  sprayAngle = 50, sprayLength = 0.4, sprayDroop = 6,
  radius = { tip = 0.009, exponent = 2.3 },
  mesh = { sides = 7, color = "#6b4a36", bark = "plated" },
  leaves = { perTip = {6, 10}, size = 0.34, width = 0.8, maxDepth = 2,
             colors = {"#27462a", "#46703c"}, shape = "needles",
             backColor = "#8caa78", translucency = 0.1 },
}
