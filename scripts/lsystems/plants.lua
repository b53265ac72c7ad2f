-- The bracketed plants of ABOP fig. 1.24 (a-f): edge rewriting (a-c) and node rewriting
-- (d-f), drawn by the default turtle in the plane facing +Z.
local p = pge.params{
  variant = {"a", doc = "a..f (ABOP fig. 1.24)"},
  n = {-1, min = -1, max = 9, doc = "derivation steps (-1: the book's)"},
}

local figures = {
  a = {axiom = "F", rules = {"F -> F[+F]F[-F]F"}, n = 5, angle = 25.7},
  b = {axiom = "F", rules = {"F -> F[+F]F[-F][F]"}, n = 5, angle = 20},
  c = {axiom = "F", rules = {"F -> FF-[-F+F+F]+[+F-F-F]"}, n = 4, angle = 22.5},
  d = {axiom = "X", rules = {"X -> F[+X]F[-X]+X", "F -> FF"}, n = 7, angle = 20},
  e = {axiom = "X", rules = {"X -> F[+X][-X]FX", "F -> FF"}, n = 7, angle = 25.7},
  f = {axiom = "X", rules = {"X -> F-[[X]+X]+F[+FX]-X", "F -> FF"}, n = 5, angle = 22.5},
}
local fig = figures[p.variant]
if not fig then error("variant must be a..f, not '" .. tostring(p.variant) .. "'") end

local plant = pge.LSystem("fig 1.24" .. p.variant)
plant:createInstance(function()
  return pge.turtle{ angle = fig.angle, width = 0.6, sides = 5 }
end)
plant:axiom(fig.axiom)
for _, r in ipairs(fig.rules) do plant:rule(r) end
plant:iterations(p.n >= 0 and p.n or fig.n)
return plant
