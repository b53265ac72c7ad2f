-- A branching coral made of extrusion and metaballs (PGE thesis, Fig. 3.13, right): every
-- branch is a smooth cylinder swept by the extruder, slightly bent and tapered; the joints,
-- the tips and the foot are metaballs, so marching cubes wraps each fork in one smooth knot
-- where the cylinders meet.
local p = pge.params{
  depth = {4, min = 0, max = 7, doc = "levels of branching"},
  children = {3, min = 1, max = 6, doc = "branches at each fork"},
  length = {1.8, min = 0.1, max = 20, doc = "length of the trunk"},
  radius = {0.28, min = 0.01, max = 5, doc = "radius of the trunk"},
  resolution = {220, min = 8, max = 512, doc = "marching cubes cells along the longest side"},
}

local rng = pge.rng(pge.seed())
local e = pge.Extruder{ smooth = true, material = { color = "#e0705a", roughness = 0.7 } }
local meta = pge.Metaballs{ radius = 1 }
local mc = pge.MarchingCubes(meta, {
  resolution = p.resolution, iso = 0.5, material = { color = "#f09070", roughness = 0.6 },
})
local path, shape = e:getPathMatrix(), e:getShapeMatrix()

-- A lone particle of influence radius R shows a sphere of radius R * SURFACE at iso 0.5.
local SURFACE = math.sqrt(1 - 0.5 ^ (1 / 3))
local function knot(position, radius)
  meta:addParticle(position, 1, radius / SURFACE)
end

local function branch(len, r, level)
  e:push()
  shape:reset()
  e:polygon(14, r)
  local segments, taper = 4, 0.94
  for _ = 1, segments do
    e:extrude(len / segments)
    path:rotateX(rng:range(-9, 9))
    path:rotateZ(rng:range(-9, 9))
    shape:scale(taper)
  end
  local tip_radius = r * taper ^ segments
  if level < p.depth then
    knot(e:position(), tip_radius * 1.45)   -- the fork's knot covers the children's bases
    local turn = rng:range(0, 360)
    for k = 1, p.children do
      e:push()
      path:rotateY(turn + k * 360 / p.children + rng:range(-20, 20))
      path:rotateZ(rng:range(22, 42))
      branch(len * rng:range(0.7, 0.9), tip_radius * 0.85, level + 1)
      e:pop()
    end
  else
    knot(e:position(), tip_radius * 1.7)    -- a polyp at the tip
  end
  e:pop()
end

-- The foot: a flattened cluster of metaballs the trunk rises from.
for i = 0, 5 do
  local a = math.rad(i * 60 + rng:range(-15, 15))
  knot({0.35 * math.cos(a), 0.05, 0.35 * math.sin(a)}, p.radius * 1.3)
end
knot({0, 0.1, 0}, p.radius * 1.6)
branch(p.length, p.radius, 0)

local model = pge.model()
model:add(e)
model:add(mc)
return model
