-- A tree grown in a revolved profile drawn by the user: a vase-shaped crown (elm-like),
-- narrow where the branches leave the trunk and wide at the top. The profile is a list of
-- {r, y} points around the vertical axis, closed from the last point back to the first.
local p = pge.params{
  points = {3000, min = 100, max = 200000, doc = "attraction points"},
  flare = {5.0, min = 1, max = 15, doc = "crown radius at its widest (m)"},
}

local profile = {
  {0.0, 3.0}, {0.8, 3.0}, {2.5, 5.0}, {p.flare * 0.9, 7.5}, {p.flare, 9.0},
  {p.flare * 0.8, 10.3}, {p.flare * 0.4, 11.0}, {0.0, 11.2},
}

return pge.SpaceColonization{
  envelope = pge.shape.revolve{ profile = profile },
  points = p.points,
  step = 0.3, influence = 2.2, kill = 0.6,
  tropism = {0, 0.15, 0},
  radius = { tip = 0.02, exponent = 2.3 },
  smoothing = 0.4,
  mesh = { sides = 7, mergeStraight = 5 },
  leaves = { perTip = {4, 6}, size = 0.09, perCard = 12, maxDepth = 2, along = { spacing = 0.15 }, colors = {"#35621f", "#6c8f2b"} },
}
