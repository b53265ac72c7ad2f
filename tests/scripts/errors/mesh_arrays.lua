-- 8 numbers are not whole vertices.
return pge.mesh{
  positions = {0, 0, 0, 1, 0, 0, 0, 1},
  indices = {0, 1, 2},
}
