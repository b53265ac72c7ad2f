-- Random crystal formations (PGE thesis, Fig. 3.12): hexagonal prisms with pointed tips,
-- extruded from a rock in random directions, each with its own size and tint. With
-- `column = 1` the same crystals are laid out regularly, in rings up a column.
local p = pge.params{
  count = {28, min = 1, max = 2000, doc = "crystals"},
  column = {0, min = 0, max = 1, doc = "0: a random cluster; 1: a regular column"},
  length = {3.5, min = 0.1, max = 100, doc = "longest crystal"},
  radius = {0.35, min = 0.01, max = 10, doc = "thickest crystal"},
  spread = {55, min = 0, max = 90, doc = "largest tilt from the vertical, degrees"},
}

local rng = pge.rng(pge.seed())
local e = pge.Extruder{ material = { roughness = 0.15, metallic = 0.0 } }
local path, shape = e:getPathMatrix(), e:getShapeMatrix()

-- A tint between ice blue and amethyst.
local function tint(t)
  local a, b = {0.70, 0.86, 0.96}, {0.80, 0.66, 0.95}
  local c = {}
  for i = 1, 3 do c[i] = a[i] + (b[i] - a[i]) * t end
  return string.format("#%02x%02x%02x", math.floor(c[1] * 255), math.floor(c[2] * 255), math.floor(c[3] * 255))
end

-- One crystal along the path's +Y: a hexagonal prism and a six-sided point.
local function crystal(len, r)
  e:push()
  e:setColor(tint(rng:uniform()))
  path:rotateY(rng:range(0, 60))            -- the hexagon's own twist
  e:polygon(6, r)
  shape:push()
  e:extrude(len)
  shape:scale(0)
  e:extrude(r * rng:range(1.2, 2.0))        -- the termination collapses to a point
  shape:pop()
  e:pop()
end

-- The rock the cluster grows from: an irregular slab that narrows upwards.
local function rock(radius)
  e:push()
  e:setColor("#6b6258")
  e:clearShape()
  for i = 0, 11 do
    local a = math.rad(i * 30)
    local rr = radius * rng:range(0.75, 1.1)
    e:addPoint2(rr * math.cos(a), -rr * math.sin(a))
  end
  shape:push()
  e:extrude(0.25)
  shape:scale(0.8)
  e:extrude(0.25)
  shape:pop()
  e:pop()
end

if p.column == 0 then
  rock(2.2)
  path:advance(0.3)
  for i = 1, p.count do
    e:push()
    local a, d = rng:range(0, 360), 1.6 * math.sqrt(rng:uniform())
    path:translate(d * math.cos(math.rad(a)), 0, -d * math.sin(math.rad(a)))
    path:rotateY(rng:range(0, 360))
    path:rotateZ(rng:range(0, p.spread) * (0.4 + 0.6 * d / 1.6))   -- outer ones lean more
    local size = rng:range(0.35, 1.0)
    crystal(p.length * size, p.radius * rng:range(0.5, 1.0) * (0.4 + 0.6 * size))
    e:pop()
  end
else
  -- A stem with rings of crystals: six per ring, turned by half a step each ring.
  local rings = math.max(1, math.ceil(p.count / 6))
  e:push()
  e:setColor("#6b6258")
  e:polygon(8, p.radius * 1.2)
  e:extrude(rings * p.radius * 3 + p.length * 0.3)
  e:pop()
  local placed = 0
  for ring = 0, rings - 1 do
    local size = 1 - 0.6 * ring / rings
    for k = 0, 5 do
      if placed < p.count then
        placed = placed + 1
        e:push()
        path:advance(ring * p.radius * 3 + 0.2)
        path:rotateY(k * 60 + (ring % 2) * 30)
        path:rotateZ(p.spread)
        crystal(p.length * size, p.radius * size)
        e:pop()
      end
    end
  end
end
return e
