-- A budget with near > far.
local counts = pge.lod.budget{ distances = {3}, leaves = 100, total = 50, near = 100, far = 10 }
return pge.model()
