-- A small broadleaf tree of about 20,000 triangles with leaves, for the end-to-end bench.
return pge.SpaceColonization{
  envelope = pge.shape.ellipsoid{ center = {0, 4.5, 0}, radii = {2.5, 2, 2.5} },
  points = 3500,
  step = 0.2, influence = 1.4, kill = 0.35,
  radius = { tip = 0.02, exponent = 2.3 },
  mesh = { sides = 7 },
  leaves = { perTip = {4, 6}, size = 0.3, maxDepth = 1 },
}
