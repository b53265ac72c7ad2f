-- The cities of the ML-System paper (§5.1, Figs. 1-3): an L-system whose symbols drive the
-- extruder. The back row uses the `City` rule: a city of n buildings is a city of n-1, a
-- translation and a copy of the same Building. The front row uses `RandCity`, the same rule
-- with a Building whose size, column count and height, spacing, roof and steps are drawn at
-- random (a stochastic L-system: the draws come from the instance's own generator). Each
-- Building is then rewritten into its parts (floor, colonnade, architrave, roof), which the
-- interpretation rules build.
local p = pge.params{
  identical = {3, min = 0, max = 40, doc = "buildings in the back row (City)"},
  random = {5, min = 0, max = 40, doc = "buildings in the front row (RandCity)"},
  gap = {10.0, min = 0, max = 100, doc = "space between buildings"},
}
local arch = require("lib.architecture")

-- The Building every `City` copies (the thesis' default values).
local default = {
  width = 4, length = 6, column_height = 8, column_separation = 5, roof_height = 3, steps = 2,
}

local function rand_int(n) return math.floor(pge.random() * n) end
local function rand_range(a, b) return a + (b - a) * pge.random() end

local obj = pge.LSystem("city")
local back_depth = select(2, arch.footprint(default))
obj:axiom{ Push{}, City{p.identical}, Pop{}, T{0, back_depth + p.gap}, RandCity{p.random} }
obj:iterations(math.max(p.identical, p.random) + 1)
obj:interpretEveryStep(false)

obj:createInstance(function()
  local city = {}
  function city:reset()
    self.e = pge.Extruder{ material = { roughness = 0.85 } }
  end
  function city:model() return self.e:model() end
  city:reset()
  return city
end)

obj:RRule("City", function(c)
  if c[1] > 0 then
    return { City{c[1] - 1}, T{arch.footprint(default) + p.gap, 0}, Building{default} }
  end
end)

obj:RRule("RandCity", function(c)
  if c[1] > 0 then
    local b = {
      width = rand_int(5) + 3,
      length = rand_int(8) + 4,
      column_height = rand_range(5, 12),
      column_separation = rand_range(3, 6),
      roof_height = rand_range(2, 4),
      steps = rand_int(4) + 1,
    }
    return { RandCity{c[1] - 1}, T{arch.footprint(b) + p.gap, 0}, Building{b} }
  end
end)

-- A building becomes its parts (floor, colonnade, architrave, roof): its footprint ends at
-- the current position along X and starts at the row's line along Z, so rows of any depth
-- never overlap.
obj:RRule("Building", function(t)
  local w, d = arch.footprint(t[1])
  local out = { Push{}, T{-w / 2, d / 2} }
  for _, part in ipairs(arch.parts(t[1], "gable")) do out[#out + 1] = part end
  out[#out + 1] = Pop{}
  return out
end)

arch.interpretation(obj)
return obj
