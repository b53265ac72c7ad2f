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

-- A building becomes its parts: its footprint ends at the current position along X and
-- starts at the row's line along Z, so rows of any depth never overlap.
-- (Each part gets the building's table as its first parameter: a table passed as a symbol's
-- own parameter table would be shared by all of them.)
obj:RRule("Building", function(t)
  local b = t[1]
  local w, d = arch.footprint(b)
  return { Push{}, T{-w / 2, d / 2}, Floor{b}, Colonnade{b}, Architrave{b}, Roof{b}, Pop{} }
end)

local function path() return this.e:getPathMatrix() end

obj:IRule("Push", function() this.e:push() return true end)
obj:IRule("Pop", function() this.e:pop() return true end)
obj:IRule("T", function(t) path():translate(t[1], 0, t[2]) return true end)

obj:IRule("Floor", function(t)
  local b = t[1]
  local w, d = arch.footprint(b)
  for s = 1, b.steps do
    local grow = (b.steps - s + 1) * 0.6
    arch.box(this.e, w + 2 * grow, d + 2 * grow, 0.35, arch.colors.step)
    path():advance(0.35)
  end
  arch.box(this.e, w, d, 0.35, arch.colors.stone)
  path():advance(0.35)
  return true
end)

obj:IRule("Colonnade", function(t)
  local b = t[1]
  local sep = b.column_separation
  local r = math.min(b.column_height / 14, sep * 0.18)
  for i = 0, b.width - 1 do
    for j = 0, b.length - 1 do
      if i == 0 or j == 0 or i == b.width - 1 or j == b.length - 1 then
        this.e:push()
        path():translate((i - (b.width - 1) / 2) * sep, 0, (j - (b.length - 1) / 2) * sep)
        arch.column(this.e, b.column_height, r)
        this.e:pop()
      end
    end
  end
  path():advance(b.column_height)
  return true
end)

obj:IRule("Architrave", function(t)
  local b = t[1]
  local w, d = arch.footprint(b)
  arch.box(this.e, w, d, 0.1 * b.column_height, arch.colors.beam)
  path():advance(0.1 * b.column_height)
  return true
end)

obj:IRule("Roof", function(t)
  local b = t[1]
  local w, d = arch.footprint(b)
  arch.gable(this.e, w, d, b.roof_height, 0.3)
  return true
end)

return obj
