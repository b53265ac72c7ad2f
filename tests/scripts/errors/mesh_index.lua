-- Index 3 does not exist: there are three vertices (0, 1, 2).
return pge.mesh{
  positions = {0, 0, 0, 1, 0, 0, 0, 1, 0},
  indices = {0, 1, 3},
}
