-- The tower of the ML-System paper (Fig. 1) and the thesis (Fig. 3.9): one building block,
-- a colonnaded storey with its podium and architrave, composed into a tower. Each storey
-- stands on the one below and is the same block in a frame scaled by `taper`; the last
-- carries a spire.
local p = pge.params{
  floors = {5, min = 1, max = 20, doc = "storeys"},
  columns = {4, min = 2, max = 12, doc = "columns per side of the first storey"},
  height = {6.0, min = 1, max = 50, doc = "column height of the first storey"},
  separation = {3.0, min = 1, max = 20, doc = "distance between columns"},
  taper = {0.72, min = 0.3, max = 1, doc = "scale of each storey relative to the one below"},
}

local arch = require("lib.architecture")
local e = pge.Extruder{ material = { roughness = 0.85 } }
local path = e:getPathMatrix()

local block = {
  width = p.columns, length = p.columns, column_height = p.height,
  column_separation = p.separation, roof_height = p.height * 1.2, steps = 2,
}
for floor = 1, p.floors do
  local last = floor == p.floors
  arch.building(e, block, last and "spire" or "none")
  path:advance(arch.height(block))
  path:scale(p.taper)
end
return e
