-- Exercises the support library; returns a tiny mesh whose name encodes the checks.
local p = pge.params{ a = 1, b = {2.5, min = 0, max = 10, doc = "b"}, flag = false, word = "oak" }
local v = pge.vec3(1, 2, 3) + {1, 1, 1}
assert(v.x == 2 and v.y == 3 and v.z == 4, "vec3 add")
assert(math.abs((v * 2):length() - 2 * v:length()) < 1e-5, "vec3 scale")
assert(pge.vec3(1, 0, 0):cross({0, 1, 0}).z == 1, "cross")
local q = pge.quat.axisAngle({0, 1, 0}, 90)
local r = q * pge.vec3(1, 0, 0)
assert(math.abs(r.z + 1) < 1e-5, "quat rotate")
local m = pge.mat4.translate{1, 0, 0} * pge.mat4.scale(2)
local t = m:transformPoint{1, 1, 1}
assert(t.x == 3 and t.y == 2, "mat4")
local rng = pge.rng(42)
local x = rng:uniform()
assert(x >= 0 and x < 1)
local k = rng:int(1, 3)
assert(k >= 1 and k <= 3)
assert(pge.rng(42):uniform() == x, "rng repeats")
local n = pge.noise.perlin(0.3, 0.7)
assert(n >= -1 and n <= 1)
assert(pge.seed() >= 0)
local name = string.format("a=%s b=%s flag=%s word=%s r=%.6f", p.a, p.b, tostring(p.flag), p.word, pge.random())
return pge.mesh{ positions = {0, 0, 0, 1, 0, 0, 0, 1, 0}, indices = {0, 1, 2}, name = name }
