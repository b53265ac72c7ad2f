-- Used by examples/host_object.rs: plants a marker on the host's heightfield every few
-- metres, asking the host (pge.world) for the ground height and reporting each plant back.
local box = require("../scripts/examples/lib/box")
local world = pge.world
local model = pge.model()
local extent = world:extent()
for x = 1, extent - 1, 2.5 do
  for z = 1, extent - 1, 2.5 do
    local y = world:height(x, z)
    world:plant(x, y, z)
    model:add(box.mesh(y > 0 and "#4f8a3c" or "#8a6d3c"), pge.mat4.translate{x, y + 0.25, z} * pge.mat4.scale(0.5))
  end
end
return model
