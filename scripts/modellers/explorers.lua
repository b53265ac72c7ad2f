-- Explorers (ML-System paper §5.3, Fig. 6; PGE thesis Fig. 3.15): an open L-system whose
-- rules read and write an image. The map (explorers_map.png) marks target regions in
-- magenta. Each explorer X, with a position and a heading, checks the colour under it: on
-- the target colour it is rewritten as a plant P, which grows there; otherwise it goes on,
-- turning at random now and then. It may not leave the map nor step on a cell held by
-- another explorer or a plant: the rewriting rule asks the world, and because every module
-- is interpreted as soon as it is produced, it sees the moves of the explorers before it in
-- the same step. The interpretation draws each explorer's trail on the map, so the image
-- records where they have been; it is saved to `out` and lies under the model as its ground.
-- Each step is a frame: `pge run explorers.lua --steps k`.
local p = pge.params{
  explorers = {16, min = 1, max = 500, doc = "explorers"},
  steps = {150, min = 1, max = 5000, doc = "frames (derivation steps)"},
  turn = {0.2, min = 0, max = 1, doc = "chance of a new heading at each step"},
  map = {"explorers_map.png", doc = "the environment image (targets in #ff00ff)"},
  out = {"", doc = "a PNG file to save the map with the trails to (relative; \"\" for none)"},
}

local TARGET, TRAIL = "#ff00ff", "#f2eed8"
local headings = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}}

-- The world: the map and who holds which cell persist across steps; the drawing of the
-- explorers and plants is made again at every step (reset).
local world = { map = pge.Image.load(p.map), cells = {} }
local W = world.map:width()
local function cell(x, y) return y * W + x end
function world:reset()
  self.marks = pge.Lines{ color = "#ffffff", width = 0.08 }
  self.plants = pge.Extruder{ material = { roughness = 0.9 } }
end
function world:model()
  if p.out ~= "" then self.map:save(p.out) end
  local m = pge.model()
  m:add(self.map)
  m:add(self.marks)
  m:add(self.plants)
  return m
end
world:reset()

-- The explorers start on free cells away from the targets.
local rng = pge.rng(pge.seed())
local axiom = {}
while #axiom < p.explorers do
  local x, y = rng:int(0, W - 1), rng:int(0, world.map:height() - 1)
  if not world.cells[cell(x, y)] and world.map:getHex(x, y) ~= TARGET then
    world.cells[cell(x, y)] = true
    axiom[#axiom + 1] = X{x = x, y = y, h = rng:int(1, 4)}
  end
end

local obj = pge.LSystem("explorers")
obj:axiom(axiom)
obj:iterations(p.steps)
obj:createInstance(function() return world end)

obj:RRule("X", function(e)
  if this.map:getHex(e.x, e.y) == TARGET then
    return P{x = e.x, y = e.y, age = 0}
  end
  local h = e.h
  if pge.random() < p.turn then
    h = (h + (pge.random() < 0.5 and 0 or 2)) % 4 + 1   -- a quarter turn left or right
  end
  local nx, ny = e.x + headings[h][1], e.y + headings[h][2]
  if this.map:inside(nx, ny) and not this.cells[cell(nx, ny)] then
    return X{x = nx, y = ny, h = h, px = e.x, py = e.y}
  end
  return X{x = e.x, y = e.y, h = h % 4 + 1}            -- blocked: turn and wait
end)

obj:RRule("P", function(q)
  if q.age < 12 then return P{x = q.x, y = q.y, age = q.age + 1} end
end)

-- Moving: release the old cell, hold the new one, draw the trail where it was.
obj:IRule("X", function(e)
  if e.px then
    this.cells[cell(e.px, e.py)] = nil
    this.map:set(e.px, e.py, TRAIL)
  end
  this.cells[cell(e.x, e.y)] = true
  local c = pge.vec3(e.x + 0.5, 0, e.y + 0.5)
  this.marks:add(c, c + pge.vec3(0, 2, 0))
  this.marks:add(c + pge.vec3(-0.4, 0.05, 0), c + pge.vec3(0.4, 0.05, 0))
  this.marks:add(c + pge.vec3(0, 0.05, -0.4), c + pge.vec3(0, 0.05, 0.4))
  return true
end)

-- A plant: a stem and a crown that grow with its age.
obj:IRule("P", function(q)
  local e, s = this.plants, 0.3 + 0.7 * math.min(q.age, 12) / 12
  local path, shape = e:getPathMatrix(), e:getShapeMatrix()
  e:push()
  path:translate(q.x + 0.5, 0, q.y + 0.5)
  e:setColor("#6b4a2b")
  e:polygon(6, 0.2 * s)
  e:extrude(1.2 * s)
  e:setColor("#2f8f3a")
  e:polygon(8, 1.3 * s)
  shape:push()
  e:extrude(0.6 * s)
  shape:scale(0)
  e:extrude(2.6 * s)
  shape:pop()
  e:pop()
  return true
end)
return obj
