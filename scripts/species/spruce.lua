-- An evergreen grown by nutrient transport: a strongly asymmetric split (ratio 0.85) keeps
-- a leader going straight up while light side branches turn out flat, as seed 001 shows.
local p = pge.params{
  steps = {110, min = 1, max = 400, doc = "feedings"},
  ratio = {0.85, min = 0.5, max = 0.95, doc = "share of the feed for the leader"},
}

return pge.Growth{
  ratio = p.ratio, spread = 0.45, splitsize = 1.5, splitdecay = 0.03,
  directedness = 0.6, localdepth = 3, feed = 1,
  steps = p.steps,
  scale = 0.45, girth = 0.25,
  mesh = { sides = 6, color = "#4a3a2e" },
  leaves = { perTip = {6, 10}, size = 0.3, width = 0.2, maxDepth = 2,
             colors = {"#1f4a2a", "#3d6b3a"} },
}
