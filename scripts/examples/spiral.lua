-- A spiral staircase of boxes: pge.mesh, pge.model, pge.mat4 and the parameters.
local p = pge.params{
  count = {48, min = 1, max = 2000, doc = "number of boxes"},
  turns = {3, min = 0.1, max = 50, doc = "turns of the spiral"},
  radius = {4.0, min = 0, max = 100, doc = "distance of the boxes from the axis"},
  rise = {0.25, min = 0, max = 10, doc = "height gained per box"},
  jitter = {0.15, min = 0, max = 1, doc = "random size variation"},
}

local box = require("lib.box")
local model = pge.model()
for i = 0, p.count - 1 do
  local t = i / p.count
  local angle = t * p.turns * 360
  local s = 1 + (pge.random() - 0.5) * 2 * p.jitter
  local m = pge.mat4.rotate({0, 1, 0}, angle)
            * pge.mat4.translate{p.radius, i * p.rise, 0}
            * pge.mat4.scale(s)
  model:add(box.mesh(string.format("#%02x%02x%02x", 60 + math.floor(180 * t), 120, 220 - math.floor(160 * t))), m)
end
return model
