-- An unknown key inside lod.
return pge.SpaceColonization{
  envelope = pge.shape.sphere{ center = {0, 4, 0}, radius = 2 },
  points = 300, step = 0.3, influence = 2, kill = 0.5, leaves = true,
  lod = { sector = 4 },
}
