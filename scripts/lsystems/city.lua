-- A city of blocks in the style of the PGE thesis: rewriting rules (RRules) split a block
-- into lots with random proportions drawn from the instance's generator, lots become
-- buildings with random heights (taller near the centre), and interpretation rules (IRules)
-- call the instance, a small modeller that stacks boxes into a model.
local p = pge.params{
  size = {60.0, min = 10, max = 1000, doc = "side of the city"},
  lot = {8.0, min = 1, max = 100, doc = "blocks smaller than this become lots"},
  street = {1.5, min = 0, max = 20, doc = "street width"},
  height = {30.0, min = 1, max = 200, doc = "tallest building"},
  steps = {12, min = 0, max = 30, doc = "derivation steps"},
}
local box = require("examples.lib.box")
local palette = {"#c9c2b8", "#a7b4c2", "#d8cfa8", "#9aa39a", "#c4a58f"}

local city = pge.LSystem("city")
city:createInstance(function()
  local modeller = {}
  function modeller:reset() self.parts = pge.model() self.count = 0 end
  -- A building: a box on the ground, plus a narrower top storey on tall ones.
  function modeller:building(x, z, w, d, h, colour)
    local mesh = box.mesh(palette[colour])
    self.parts:add(mesh, pge.mat4.translate{x, h / 2, z} * pge.mat4.scale{w, h, d})
    if h > 10 then
      self.parts:add(mesh, pge.mat4.translate{x, h + 1, z} * pge.mat4.scale{w * 0.6, 2, d * 0.6})
    end
    self.count = self.count + 1
  end
  function modeller:model() return self.parts end
  modeller:reset()
  return modeller
end)

local half = p.size / 2
city:axiom{ Block{ x = -half, z = -half, w = p.size, d = p.size } }

-- Split a block across its longer side at a random fraction, leaving a street.
city:RRule("Block", function(b)
  if b.w < p.lot and b.d < p.lot then
    return Lot{ x = b.x, z = b.z, w = b.w, d = b.d }
  end
  local t = 0.35 + 0.3 * pge.random()
  local s = p.street / 2
  if b.w >= b.d then
    local w1 = b.w * t
    return { Block{ x = b.x, z = b.z, w = w1 - s, d = b.d },
             Block{ x = b.x + w1 + s, z = b.z, w = b.w - w1 - s, d = b.d } }
  end
  local d1 = b.d * t
  return { Block{ x = b.x, z = b.z, w = b.w, d = d1 - s },
           Block{ x = b.x, z = b.z + d1 + s, w = b.w, d = b.d - d1 - s } }
end)

-- A lot becomes a building: set back from the street, taller toward the centre.
city:RRule("Lot", function(l)
  local cx, cz = l.x + l.w / 2, l.z + l.d / 2
  local centrality = 1 - math.min(1, math.sqrt(cx * cx + cz * cz) / half)
  local h = 2 + (p.height - 2) * centrality * (0.5 + 0.5 * pge.random())
  return Building{ x = cx, z = cz, w = l.w * 0.8, d = l.d * 0.8, h = h,
                   colour = 1 + math.floor(pge.random() * #palette) }
end)

city:IRule("Building", function(b)
  this:building(b.x, b.z, b.w, b.d, b.h, b.colour)
  return true
end)

city:iterations(p.steps)
city:interpretEveryStep(false)
return city
