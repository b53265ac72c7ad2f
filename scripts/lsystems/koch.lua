-- ABOP Koch constructions (Prusinkiewicz & Lindenmayer, The Algorithmic Beauty of Plants,
-- figs. 1.7 and 1.9): an axiom square whose edges are replaced by a generator polyline.
-- `variant` picks the figure: "island" (fig. 1.7a, quadratic Koch island), "lakes" (fig. 1.8,
-- islands and lakes: `f` moves without drawing), "snowflake" (the Koch snowflake, 60 degrees),
-- or "a".."f" (the six curves of fig. 1.9).
local p = pge.params{
  variant = {"island", doc = "island, lakes, snowflake or a..f (ABOP fig. 1.9)"},
  n = {-1, min = -1, max = 8, doc = "derivation steps (-1: the book's)"},
}

local figures = {
  island = {axiom = "F-F-F-F", rules = {"F -> F-F+F+FF-F-F+F"}, n = 3, angle = 90},
  lakes = {axiom = "F+F+F+F", rules = {"F -> F+f-FF+F+FF+Ff+FF-f+FF-F-FF-Ff-FFF", "f -> ffffff"},
           n = 2, angle = 90},
  snowflake = {axiom = "F--F--F", rules = {"F -> F+F--F+F"}, n = 4, angle = 60},
  a = {axiom = "F-F-F-F", rules = {"F -> FF-F-F-F-F-F+F"}, n = 4, angle = 90},
  b = {axiom = "F-F-F-F", rules = {"F -> FF-F-F-F-FF"}, n = 4, angle = 90},
  c = {axiom = "F-F-F-F", rules = {"F -> FF-F+F-F-FF"}, n = 3, angle = 90},
  d = {axiom = "F-F-F-F", rules = {"F -> FF-F--F-F"}, n = 4, angle = 90},
  e = {axiom = "F-F-F-F", rules = {"F -> F-FF--F-F"}, n = 5, angle = 90},
  f = {axiom = "F-F-F-F", rules = {"F -> F-F+F-F-F"}, n = 4, angle = 90},
}
local fig = figures[p.variant]
if not fig then
  error("variant must be island, lakes, snowflake or a..f, not '" .. tostring(p.variant) .. "'")
end

local koch = pge.LSystem("koch " .. p.variant)
koch:createInstance(function()
  return pge.turtle{ angle = fig.angle, width = 0.25, sides = 4 }
end)
koch:axiom(fig.axiom)
for _, r in ipairs(fig.rules) do koch:rule(r) end
koch:iterations(p.n >= 0 and p.n or fig.n)
return koch
