-- Random crystal formations (PGE thesis, Fig. 3.12) as a stochastic L-system over the
-- extruder: a `Cluster` is rewritten into a rock and `count` crystals, each in its own
-- branch (Push, Orient, Crystal, Pop) with a random position, lean, length, thickness and
-- tint drawn by the rule from the instance's generator. A crystal is a hexagonal prism with
-- a pointed termination. With `column = 1` a `Column` is rewritten into a stem and rings of
-- six crystals, regularly turned and shrinking upwards (the figure's right side).
local p = pge.params{
  count = {28, min = 1, max = 2000, doc = "crystals"},
  column = {0, min = 0, max = 1, doc = "0: a random cluster; 1: a regular column"},
  length = {3.5, min = 0.1, max = 100, doc = "longest crystal"},
  radius = {0.35, min = 0.01, max = 10, doc = "thickest crystal"},
  spread = {55, min = 0, max = 90, doc = "largest tilt from the vertical, degrees"},
}

local function range(a, b) return a + (b - a) * pge.random() end

local obj = pge.LSystem("crystals")
obj:axiom{ p.column == 1 and Column{} or Cluster{} }
obj:iterations(1)

obj:createInstance(function()
  local inst = {}
  function inst:reset() self.e = pge.Extruder{ material = { roughness = 0.15 } } end
  function inst:model() return self.e:model() end
  inst:reset()
  return inst
end)

obj:RRule("Cluster", function()
  local out = { Rock{radius = 2.2, shape = {}} }
  for i = 1, 12 do out[1].shape[i] = range(0.75, 1.1) end
  for _ = 1, p.count do
    local d = 1.6 * math.sqrt(pge.random())
    local size = range(0.35, 1.0)
    for _, m in ipairs{
      Push{},
      Orient{
        angle = range(0, 360), distance = d, turn = range(0, 360),
        tilt = range(0, p.spread) * (0.4 + 0.6 * d / 1.6),   -- outer ones lean more
      },
      Crystal{
        length = p.length * size, radius = p.radius * range(0.5, 1.0) * (0.4 + 0.6 * size),
        tint = pge.random(), twist = range(0, 60), tip = range(1.2, 2.0),
      },
      Pop{},
    } do out[#out + 1] = m end
  end
  return out
end)

obj:RRule("Column", function()
  local rings = math.max(1, math.ceil(p.count / 6))
  local out = { Stem{height = rings * p.radius * 3 + p.length * 0.3} }
  local placed = 0
  for ring = 0, rings - 1 do
    local size = 1 - 0.6 * ring / rings
    for k = 0, 5 do
      if placed < p.count then
        placed = placed + 1
        for _, m in ipairs{
          Push{},
          Orient{height = ring * p.radius * 3 + 0.2, turn = k * 60 + (ring % 2) * 30, tilt = p.spread},
          Crystal{length = p.length * size, radius = p.radius * size, tint = pge.random(), twist = 0, tip = 1.6},
          Pop{},
        } do out[#out + 1] = m end
      end
    end
  end
  return out
end)

-- A tint between ice blue and amethyst.
local function tint(t)
  local a, b = {0.70, 0.86, 0.96}, {0.80, 0.66, 0.95}
  local c = {}
  for i = 1, 3 do c[i] = math.floor((a[i] + (b[i] - a[i]) * t) * 255) end
  return string.format("#%02x%02x%02x", c[1], c[2], c[3])
end

obj:IRule("Push", function() this.e:push() return true end)
obj:IRule("Pop", function() this.e:pop() return true end)

obj:IRule("Orient", function(o)
  local path = this.e:getPathMatrix()
  if o.distance then
    local a = math.rad(o.angle)
    path:translate(o.distance * math.cos(a), 0.3, -o.distance * math.sin(a))
  else
    path:advance(o.height)
  end
  path:rotateY(o.turn)
  path:rotateZ(o.tilt)
  return true
end)

obj:IRule("Crystal", function(c)
  local e = this.e
  local path, shape = e:getPathMatrix(), e:getShapeMatrix()
  e:setColor(tint(c.tint))
  path:rotateY(c.twist)                     -- the hexagon's own twist
  e:polygon(6, c.radius)
  e:extrude(c.length)
  shape:scale(0)
  e:extrude(c.radius * c.tip)               -- the termination collapses to a point
  return true
end)

-- The rock the cluster grows from: an irregular slab that narrows upwards.
obj:IRule("Rock", function(r)
  local e = this.e
  e:push()
  e:setColor("#6b6258")
  e:clearShape()
  for i, k in ipairs(r.shape) do
    local a = math.rad((i - 1) * 30)
    e:addPoint2(r.radius * k * math.cos(a), -r.radius * k * math.sin(a))
  end
  e:extrude(0.25)
  e:getShapeMatrix():scale(0.8)
  e:extrude(0.25)
  e:pop()
  return true
end)

obj:IRule("Stem", function(s)
  local e = this.e
  e:push()
  e:setColor("#6b6258")
  e:polygon(8, p.radius * 1.2)
  e:extrude(s.height)
  e:pop()
  return true
end)
return obj
