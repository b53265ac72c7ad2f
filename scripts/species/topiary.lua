-- A tree grown inside a closed mesh read from a file: data/crown.obj is a three-lobed
-- cloud (a displaced icosphere), like a clipped topiary crown.
local p = pge.params{
  points = {3000, min = 100, max = 200000, doc = "attraction points"},
  mode = {"fill", doc = "fill, surround or vertices"},
}

return pge.SpaceColonization{
  envelope = pge.shape.mesh{ path = "data/crown.obj" },
  mode = p.mode,
  thickness = 0.8,
  points = p.points,
  step = 0.2, influence = 1.5, kill = 0.4,
  radius = { tip = 0.018, exponent = 2.3 },
  mesh = { sides = 6, mergeStraight = 5, color = "#54463a" },
  leaves = { perTip = {5, 7}, size = 0.04, perCard = 12, maxDepth = 2, along = { spacing = 0.06 }, colors = {"#24551c", "#3f7a2a"} },
}
