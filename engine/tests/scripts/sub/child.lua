local p = pge.params{ size = 1 }
return p.size
