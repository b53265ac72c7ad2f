-- A budget whose near distance is negative.
local counts = pge.lod.budget{ distances = {3}, leaves = 100, roots = 5, total = 50,
                               near = -1, far = 100 }
return pge.model()
