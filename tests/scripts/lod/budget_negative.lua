-- A budget with a negative distance.
local counts = pge.lod.budget{ distances = {3, 8, -2}, leaves = 100, roots = 5, total = 50,
                               near = 10, far = 100 }
return pge.model()
