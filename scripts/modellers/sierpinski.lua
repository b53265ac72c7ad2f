-- The Sierpinski triangle built with the extruder (PGE thesis, Figs. 3.4 and 3.8; ML-System
-- paper, Fig. 3), as an L-system: a triangle S becomes a prism P carrying three half-size
-- triangles at its corners, each in its own branch (Push, Corner, S, Pop). Every derivation
-- step is one more level of the fractal (`pge run sierpinski.lua --steps k`), `depth`
-- steps by default. The corners move and scale the path matrix, so each copy is the whole
-- construction in a smaller frame. With `stacked = 0` only the last level is built, all at
-- the same height: the flat Sierpinski gasket, extruded.
local p = pge.params{
  depth = {4, min = 0, max = 8, doc = "recursion depth (derivation steps)"},
  size = {10.0, min = 0.1, max = 1000, doc = "circumradius of the largest triangle"},
  height = {1.5, min = 0.01, max = 100, doc = "height of the largest prism"},
  stacked = {1, min = 0, max = 1, doc = "1: a stepped pyramid of every level; 0: the last level only"},
}

-- An equilateral triangle of circumradius 1, a corner toward -Z.
local corners = {}
for i = 0, 2 do
  local a = math.rad(90 + 120 * i)
  corners[#corners + 1] = {math.cos(a), -math.sin(a)}
end

local obj = pge.LSystem("sierpinski")
obj:axiom{ S{0} }
obj:iterations(p.depth)

obj:createInstance(function()
  local inst = {}
  function inst:reset()
    self.e = pge.Extruder{ material = { color = "#ffffff", roughness = 0.8 } }
    for _, c in ipairs(corners) do self.e:addPoint2(c[1], c[2]) end
    local path = self.e:getPathMatrix()
    path:scale(p.size)
    path:scaleY(1 / p.size)            -- the size spreads the triangle, not the prisms' height
  end
  function inst:model() return self.e:model() end
  inst:reset()
  return inst
end)

obj:RRule("S", function(s)
  local out = { P{s[1]} }
  for i = 1, 3 do
    for _, m in ipairs{ Push{}, Corner{i}, S{s[1] + 1}, Pop{} } do out[#out + 1] = m end
  end
  return out
end)

-- A shade per level, from sandstone at the base to white at the top.
local function shade(level)
  local t = level / math.max(p.depth, 1)
  local c = function(a, b) return math.floor(a + (b - a) * t + 0.5) end
  return string.format("#%02x%02x%02x", c(190, 250), c(150, 245), c(110, 235))
end

-- A prism of the triangle at the current frame; the path ends on its top.
local function prism(level)
  this.e:start()                       -- every prism is its own closed piece
  this.e:setColor(shade(level))
  this.e:extrude(p.height)
end

-- P: a refined triangle (drawn only when stacked); S: a leaf triangle (always drawn).
obj:IRule("P", function(t)
  if p.stacked == 1 then prism(t[1]) end
  return true
end)
obj:IRule("S", function(t) prism(t[1]) return true end)

-- Push and Pop save and restore the extruder's frame (the instance is not a turtle, so
-- the branch brackets [ ] would mean nothing to it).
obj:IRule("Push", function() this.e:push() return true end)
obj:IRule("Pop", function() this.e:pop() return true end)

obj:IRule("Corner", function(t)
  local c, path = corners[t[1]], this.e:getPathMatrix()
  path:translate(c[1] * 0.5, 0, c[2] * 0.5)      -- the corner's half-size triangle
  if p.stacked == 1 then path:scale(0.5) else path:scale(0.5, 1, 0.5) end
  return true
end)
return obj
