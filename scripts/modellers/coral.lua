-- A branching coral made of extrusion and metaballs (PGE thesis, Fig. 3.13, right), as a
-- stochastic L-system: a `Branch` is rewritten into a segment (a smooth cylinder swept by
-- the extruder, bent and tapered at random) and, at its end, either a fork (a metaball knot
-- and `children` branches, each in its own Push/Pop) or a polyp (a larger metaball). The
-- foot is a cluster of metaballs. Marching cubes wraps the metaballs into one surface, so
-- each fork becomes a smooth knot where the cylinders meet. Each step grows one level.
local p = pge.params{
  depth = {4, min = 0, max = 7, doc = "levels of branching"},
  children = {3, min = 1, max = 6, doc = "branches at each fork"},
  length = {1.8, min = 0.1, max = 20, doc = "length of the trunk"},
  radius = {0.28, min = 0.01, max = 5, doc = "radius of the trunk"},
  resolution = {220, min = 8, max = 512, doc = "marching cubes cells along the longest side"},
}

local SEGMENTS, TAPER = 4, 0.94
-- A lone particle of influence radius R shows a sphere of radius R * SURFACE at iso 0.5.
local SURFACE = math.sqrt(1 - 0.5 ^ (1 / 3))
local function range(a, b) return a + (b - a) * pge.random() end

local obj = pge.LSystem("coral")
obj:axiom{ Foot{}, Branch{length = p.length, radius = p.radius, level = 0} }
obj:iterations(p.depth + 1)

obj:createInstance(function()
  local coral = {}
  function coral:reset()
    self.e = pge.Extruder{ smooth = true, material = { color = "#e0705a", roughness = 0.7 } }
    self.meta = pge.Metaballs{ radius = 1 }
    self.mc = pge.MarchingCubes(self.meta, {
      resolution = p.resolution, iso = 0.5, material = { color = "#f09070", roughness = 0.6 },
    })
  end
  function coral:model()
    local m = pge.model()
    m:add(self.e)
    m:add(self.mc)
    return m
  end
  coral:reset()
  return coral
end)

obj:RRule("Branch", function(b)
  local bends = {}
  for i = 1, SEGMENTS do bends[i] = {range(-9, 9), range(-9, 9)} end
  local tip = b.radius * TAPER ^ SEGMENTS
  local out = { Segment{length = b.length, radius = b.radius, bends = bends} }
  if b.level >= p.depth then
    out[#out + 1] = Knot{radius = tip * 1.7}            -- a polyp at the tip
    return out
  end
  out[#out + 1] = Knot{radius = tip * 1.45}             -- covers the children's bases
  local turn = range(0, 360)
  for k = 1, p.children do
    for _, m in ipairs{
      Push{},
      Turn{yaw = turn + k * 360 / p.children + range(-20, 20), tilt = range(22, 42)},
      Branch{length = b.length * range(0.7, 0.9), radius = tip * 0.85, level = b.level + 1},
      Pop{},
    } do out[#out + 1] = m end
  end
  return out
end)

obj:IRule("Push", function() this.e:push() return true end)
obj:IRule("Pop", function() this.e:pop() return true end)

obj:IRule("Turn", function(t)
  local path = this.e:getPathMatrix()
  path:rotateY(t.yaw)
  path:rotateZ(t.tilt)
  return true
end)

-- A segment: a tapering, bending cylinder; the path ends at its tip.
obj:IRule("Segment", function(s)
  local e = this.e
  local path, shape = e:getPathMatrix(), e:getShapeMatrix()
  e:start()
  shape:push()
  shape:reset()
  e:polygon(14, s.radius)
  for i = 1, SEGMENTS do
    e:extrude(s.length / SEGMENTS)
    path:rotateX(s.bends[i][1])
    path:rotateZ(s.bends[i][2])
    shape:scale(TAPER)
  end
  shape:pop()
  return true
end)

-- A metaball where the path is (unexpanded branches of the last step draw nothing).
obj:IRule("Knot", function(k)
  this.meta:addParticle(this.e:position(), 1, k.radius / SURFACE)
  return true
end)

-- The foot: a flattened cluster of metaballs the trunk rises from.
obj:IRule("Foot", function()
  for i = 0, 5 do
    local a = math.rad(i * 60 + 10 * math.sin(i * 2.3))
    this.meta:addParticle({0.35 * math.cos(a), 0.05, 0.35 * math.sin(a)}, 1, p.radius * 1.3 / SURFACE)
  end
  this.meta:addParticle({0, 0.1, 0}, 1, p.radius * 1.6 / SURFACE)
  return true
end)
return obj
