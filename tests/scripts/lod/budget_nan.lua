-- A budget with a NaN distance.
local counts = pge.lod.budget{ distances = {3, 0/0}, leaves = 100, roots = 5, total = 50,
                               near = 10, far = 100 }
return pge.model()
