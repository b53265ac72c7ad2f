-- A broad deciduous tree grown by nutrient transport (seed 001): the seed's own parameters,
-- fed 90 times. Scrub the preview's steps to watch it grow from a sapling.
local p = pge.params{
  steps = {90, min = 1, max = 400, doc = "feedings"},
  ratio = {0.6, min = 0.05, max = 0.95, doc = "share of the feed for the heavier child"},
  spread = {0.45, min = 0, max = 3, doc = "how far children turn from their parent"},
}

return pge.Growth{
  ratio = p.ratio, spread = p.spread, splitsize = 2.5, splitdecay = 0.01,
  directedness = 0.5, localdepth = 2, feed = 1,
  steps = p.steps,
  scale = 0.5, girth = 0.35,
  mesh = { sides = 7, color = "#6b5444" },
  leaves = { perTip = {4, 7}, size = 0.09, perCard = 12, maxDepth = 1, along = { spacing = 0.12 }, colors = {"#356b22", "#86a83a"} },
}
