-- A tree that avoids dense foliage strongly (directedness 0.95, a wide local search) and
-- branches wide (spread 1.1): crooked limbs at high angles, the bonsai look of seed 001.
local p = pge.params{
  steps = {80, min = 1, max = 400, doc = "feedings"},
  directedness = {0.95, min = 0, max = 1, doc = "how strongly new branches turn from dense foliage"},
}

return pge.Growth{
  ratio = 0.55, spread = 1.1, splitsize = 1.8, splitdecay = 0.02,
  directedness = p.directedness, localdepth = 5, feed = 0.8,
  steps = p.steps,
  scale = 0.35, girth = 0.45,
  mesh = { sides = 7, color = "#5a4636" },
  leaves = { perTip = {5, 9}, size = 0.05, perCard = 12, maxDepth = 1, along = { spacing = 0.06 }, colors = {"#2f5e1f", "#5f8a2a"} },
}
