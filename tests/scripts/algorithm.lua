-- A script-defined Algorithm: one box per step, stacked.
local p = pge.params{ boxes = {5, min = 1, max = 100} }
local box = require("../../scripts/examples/lib/box")
return pge.Algorithm{
  init = function(self) self.n = 0; self.model = pge.model() end,
  step = function(self)
    self.model:add(box.mesh("#aa5533"), pge.mat4.translate{0, self.n * 1.1, 0})
    self.n = self.n + 1
    return self.n < p.boxes
  end,
  finish = function(self) return self.model end,
}
