-- Architectural parts built with pge.Extruder, shared by the tower and the cities.
-- Every function builds on the extruder's current frame (the path matrix) and leaves the
-- frame where it found it (push/pop), so callers place parts by moving the path.
local M = {}

-- Sides of a column's shaft: its resolution (the thesis' low and high resolution models).
M.sides = 16

M.colors = {
  stone = "#d9cfbd", step = "#b8ad98", column = "#f0ebe0", roof = "#a0523c", beam = "#e2d8c4",
}

-- The shape: a w x d rectangle centred on the path, counter-clockwise seen from above.
function M.rect(e, w, d)
  e:clearShape()
  e:addPoint2(w / 2, d / 2)
  e:addPoint2(w / 2, -d / 2)
  e:addPoint2(-w / 2, -d / 2)
  e:addPoint2(-w / 2, d / 2)
end

-- A w x h x d box standing on the frame.
function M.box(e, w, d, h, color)
  e:push()
  e:setColor(color or M.colors.stone)
  M.rect(e, w, d)
  e:extrude(h)
  e:pop()
end

-- A column of height h and shaft radius r: plinth, torus, tapered shaft, echinus, abacus.
function M.column(e, h, r)
  local shape = e:getShapeMatrix()
  e:push()
  e:setColor(M.colors.column)
  M.rect(e, 2.6 * r, 2.6 * r)
  e:extrude(0.04 * h)                       -- plinth
  e:polygon(M.sides, 1.2 * r)
  e:extrude(0.03 * h)                       -- torus (a new piece: the point count changed)
  e:polygon(M.sides, r)
  e:extrude(0)                              -- step in to the shaft, same piece
  shape:push()
  for _ = 1, 4 do                           -- entasis: the shaft narrows upwards
    e:extrude(0.2 * h)
    shape:scale(0.96)
  end
  shape:pop()
  e:polygon(M.sides, 1.25 * r)
  e:extrude(0.05 * h)                       -- echinus flares out
  M.rect(e, 2.8 * r, 2.8 * r)
  e:extrude(0.04 * h)                       -- abacus
  e:pop()
end

-- A gable roof over a w x d rectangle: a triangle extruded along -Z.
function M.gable(e, w, d, h, overhang)
  local path = e:getPathMatrix()
  local o = overhang or 0
  e:push()
  e:setColor(M.colors.roof)
  path:translate(0, 0, d / 2 + o)
  path:rotateX(-90)                         -- local +Y now runs along -Z, local +Z is up
  e:clearShape()
  e:addPoint2(-w / 2 - o, 0)
  e:addPoint2(w / 2 + o, 0)
  e:addPoint2(0, h)
  e:extrude(d + 2 * o)
  e:pop()
end

-- A hipped (pyramid) roof with a spire: the rectangle extruded while its shape shrinks.
function M.spire(e, w, d, h)
  local shape = e:getShapeMatrix()
  e:push()
  e:setColor(M.colors.roof)
  M.rect(e, w, d)
  shape:push()
  e:extrude(0)
  shape:scale(0.15)
  e:extrude(h)
  shape:scale(0)
  e:extrude(h * 0.8)
  shape:pop()
  e:pop()
end

-- The footprint of a building: columns across (width) and along (length), their spacing.
function M.footprint(b)
  local sep = b.column_separation
  return (b.width - 1) * sep + 1.2 * sep, (b.length - 1) * sep + 1.2 * sep
end

-- The parts of a temple-like building (the thesis' Building symbol). `b` holds width and
-- length (columns), column_height, column_separation, roof_height and steps, as in the
-- thesis' RandCity rule. Each part stands on the frame and leaves the path on its top.
local STEP_H, STEP_W = 0.35, 0.6

-- The stepped podium and the stylobate the columns stand on.
function M.floor(e, b)
  local path = e:getPathMatrix()
  local w, d = M.footprint(b)
  for s = 1, b.steps do                     -- widest step first
    local grow = (b.steps - s + 1) * STEP_W
    M.box(e, w + 2 * grow, d + 2 * grow, STEP_H, M.colors.step)
    path:advance(STEP_H)
  end
  M.box(e, w, d, STEP_H, M.colors.stone)
  path:advance(STEP_H)
end

-- The colonnade on the perimeter.
function M.colonnade(e, b)
  local path = e:getPathMatrix()
  local sep, h = b.column_separation, b.column_height
  local r = math.min(h / 14, sep * 0.18)
  for i = 0, b.width - 1 do
    for j = 0, b.length - 1 do
      if i == 0 or j == 0 or i == b.width - 1 or j == b.length - 1 then
        e:push()
        path:translate((i - (b.width - 1) / 2) * sep, 0, (j - (b.length - 1) / 2) * sep)
        M.column(e, h, r)
        e:pop()
      end
    end
  end
  path:advance(h)
end

-- The architrave on the columns.
function M.architrave(e, b)
  local w, d = M.footprint(b)
  M.box(e, w, d, 0.1 * b.column_height, M.colors.beam)
  e:getPathMatrix():advance(0.1 * b.column_height)
end

-- The roof: "gable" (default), "spire" or "none".
function M.roof(e, b, kind)
  local w, d = M.footprint(b)
  if kind == "spire" then
    M.spire(e, w, d, b.roof_height)
  elseif kind ~= "none" then
    M.gable(e, w, d, b.roof_height, 0.3)
  end
end

-- The whole building at once.
function M.building(e, b, roof)
  e:push()
  M.floor(e, b)
  M.colonnade(e, b)
  M.architrave(e, b)
  M.roof(e, b, roof)
  e:pop()
end

-- What a Building symbol is rewritten into: its parts, between Push and Pop so the path
-- comes back to the ground. (Each part gets the building's table as its first parameter:
-- a table given as a symbol's own parameter table would be shared by all of them.)
function M.parts(b, roof)
  return {
    pge.sym("Push"), pge.sym("Floor", {b}), pge.sym("Colonnade", {b}),
    pge.sym("Architrave", {b}), pge.sym("Roof", {b, roof}), pge.sym("Pop"),
  }
end

-- Interpretation rules for the parts and for moving the extruder `this.e`: Push, Pop,
-- T{dx, dz} (a move on the ground), Up{h, scale} (a move up, then a scaling of the frame),
-- Floor, Colonnade, Architrave, Roof.
function M.interpretation(obj)
  local function e() return this.e end
  obj:IRule("Push", function() e():push() return true end)
  obj:IRule("Pop", function() e():pop() return true end)
  obj:IRule("T", function(t) e():getPathMatrix():translate(t[1], 0, t[2]) return true end)
  obj:IRule("Up", function(t)
    local path = e():getPathMatrix()
    path:advance(t[1])
    path:scale(t[2] or 1)
    return true
  end)
  obj:IRule("Floor", function(t) M.floor(e(), t[1]) return true end)
  obj:IRule("Colonnade", function(t) M.colonnade(e(), t[1]) return true end)
  obj:IRule("Architrave", function(t) M.architrave(e(), t[1]) return true end)
  obj:IRule("Roof", function(t) M.roof(e(), t[1], t[2]) return true end)
end

-- The height of a building from the ground to the top of its architrave.
function M.height(b)
  return (b.steps + 1) * STEP_H + 1.1 * b.column_height
end

return M
