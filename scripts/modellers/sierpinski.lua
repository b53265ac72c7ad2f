-- The Sierpinski triangle built with the extruder (PGE thesis, Fig. 3.4; ML-System paper,
-- Fig. 3): a triangular prism carries three half-size copies of itself at its corners,
-- down to `depth` levels. The recursion moves and scales the path matrix, so each copy is
-- the whole construction in a smaller frame. With `stacked = 0` only the last level is
-- built, all at the same height: the flat Sierpinski gasket, extruded.
local p = pge.params{
  depth = {4, min = 0, max = 8, doc = "recursion depth"},
  size = {10.0, min = 0.1, max = 1000, doc = "circumradius of the largest triangle"},
  height = {1.5, min = 0.01, max = 100, doc = "height of the largest prism"},
  stacked = {1, min = 0, max = 1, doc = "1: a stepped pyramid of every level; 0: the last level only"},
}

local e = pge.Extruder{ material = { color = "#d8c8a0", roughness = 0.8 } }
local path = e:getPathMatrix()

-- An equilateral triangle of circumradius 1, a corner toward -Z.
local corners = {}
for i = 0, 2 do
  local a = math.rad(90 + 120 * i)
  corners[#corners + 1] = {math.cos(a), -math.sin(a)}
  e:addPoint2(math.cos(a), -math.sin(a))
end

-- A shade per level, from sandstone at the base to white at the top.
local function shade(level)
  local t = level / math.max(p.depth, 1)
  local c = function(a, b) return math.floor(a + (b - a) * t + 0.5) end
  return string.format("#%02x%02x%02x", c(190, 250), c(150, 245), c(110, 235))
end

local function sierpinski(level)
  local build = p.stacked == 1 or level == p.depth
  e:push()
  if build then
    e:setColor(shade(level))
    e:extrude(p.height)
  end
  if level < p.depth then
    for _, c in ipairs(corners) do
      e:push()
      path:translate(c[1] * 0.5, 0, c[2] * 0.5)   -- the corner's half-size triangle
      if p.stacked == 1 then path:scale(0.5) else path:scale(0.5, 1, 0.5) end
      sierpinski(level + 1)
      e:pop()
    end
  end
  e:pop()
end

path:scale(p.size)
path:scaleY(1 / p.size)        -- the size spreads the triangle, not the prism's height
sierpinski(0)
return e
