-- 0/0 is NaN.
local v = pge.vec3(1, 2, 3)
local w = pge.vec3(0 / 0, 0, 0)
return v + w
