-- The tower of the ML-System paper (Fig. 1) and the thesis (Fig. 3.9), as an L-system over
-- the extruder: `Tower{n}` is a storey, a move up that scales the frame by `taper`, and a
-- tower of n-1 storeys; the last storey carries a spire. Each `Storey` is then rewritten
-- into the building block's parts (podium, colonnade, architrave, roof), which the
-- interpretation rules build. Each derivation step adds a storey (`--steps k`).
local p = pge.params{
  floors = {5, min = 1, max = 20, doc = "storeys"},
  columns = {4, min = 2, max = 12, doc = "columns per side of the first storey"},
  height = {6.0, min = 1, max = 50, doc = "column height of the first storey"},
  separation = {3.0, min = 1, max = 20, doc = "distance between columns"},
  taper = {0.72, min = 0.3, max = 1, doc = "scale of each storey relative to the one below"},
  sides = {16, min = 3, max = 64, doc = "sides of the columns: the model's resolution"},
}

local arch = require("lib.architecture")
arch.sides = p.sides
local block = {
  width = p.columns, length = p.columns, column_height = p.height,
  column_separation = p.separation, roof_height = p.height * 1.2, steps = 2,
}

local obj = pge.LSystem("tower")
obj:axiom{ Tower{p.floors} }
obj:iterations(p.floors + 1)

obj:createInstance(function()
  local tower = {}
  function tower:reset() self.e = pge.Extruder{ material = { roughness = 0.85 } } end
  function tower:model() return self.e:model() end
  tower:reset()
  return tower
end)

obj:RRule("Tower", function(t)
  if t[1] == 1 then return Storey{"spire"} end
  return { Storey{"none"}, Up{arch.height(block), p.taper}, Tower{t[1] - 1} }
end)

obj:RRule("Storey", function(s) return arch.parts(block, s[1]) end)

arch.interpretation(obj)
return obj
