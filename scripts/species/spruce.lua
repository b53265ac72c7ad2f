-- A spruce, grown by pge.Conifer (an excurrent tree): a straight leader that adds one
-- internode and one whorl of 4 to 6 branches a year (now and then a small branch between
-- whorls), a dense narrow cone down to the ground, lower branches long and drooping, their
-- tips bent down, every branch a flat spray of shoots and shoots of shoots (three orders)
-- under short dark needles. Scaly bark (small thin plates).
-- One step is one year: `--steps 8` is the sapling, `--stages 6,14,28` three ages.
local p = pge.params{
  height = {14, min = 3, max = 50, doc = "tree height after `years` years (m)"},
  radius = {2.8, min = 0.5, max = 10, doc = "crown radius: the longest branch (m)"},
  years = {28, min = 1, max = 200, doc = "years of growth: one internode and one whorl a year"},
}

return pge.Conifer{
  years = p.years, height = p.height, crownRadius = p.radius,
  crown = "conic", crownBase = 0.04,
  perWhorl = {4, 6}, interwhorl = {0, 1}, angle = {65, 100}, droop = 40, jitter = 0.15,
  segment = 0.22, orders = 3, bare = 0.1,
  sprayAngle = 55, sprayLength = 0.4, sprayDroop = 20,
  radius = { tip = 0.005, exponent = 2.2 },
  mesh = { sides = 6, color = "#4e3b30", bark = "scaly" },
  leaves = { perTip = {6, 9}, size = 0.2, width = 0.9, maxDepth = 2,
             colors = {"#122a1a", "#23402a"}, shape = "needles",
             backColor = "#58784e", translucency = 0.08 },
}
