-- Signal propagation in context-sensitive L-systems: the Hogeweg-Hesper plants of ABOP
-- fig. 1.31 (a-e). Each 0/1 looks at its neighbours along the axis (`+ - F` ignored, branches
-- skipped by the right context, enclosing branches climbed by the left one).
local p = pge.params{
  variant = {"a", doc = "a..e (ABOP fig. 1.31)"},
  n = {-1, min = -1, max = 40, doc = "derivation steps (-1: the book's)"},
}

-- Successors of `l < x > r` for (l, x, r) = 000, 001, 010, 011, 100, 101, 110, 111.
local figures = {
  a = {axiom = "F1F1F1", n = 30, angle = 22.5, succ = {"0", "1[+F1F1]", "1", "1", "0", "1F1", "0", "0"}},
  b = {axiom = "F1F1F1", n = 30, angle = 22.5, succ = {"1", "1[-F1F1]", "1", "1", "0", "1F1", "1", "0"}},
  c = {axiom = "F1F1F1", n = 26, angle = 25.75, succ = {"0", "1", "0", "1[+F1F1]", "0", "1F1", "0", "0"}},
  d = {axiom = "F0F1F1", n = 24, angle = 25.75, succ = {"1", "0", "0", "1F1", "1", "1[+F1F1]", "1", "0"}},
  e = {axiom = "F1F1F1", n = 26, angle = 22.5, succ = {"0", "1[-F1F1]", "1", "1", "0", "1F1", "1", "0"}},
}
local fig = figures[p.variant]
if not fig then error("variant must be a..e, not '" .. tostring(p.variant) .. "'") end

local plant = pge.LSystem("fig 1.31" .. p.variant)
plant:createInstance(function()
  return pge.turtle{ angle = fig.angle, width = 0.4, sides = 5 }
end)
plant:axiom(fig.axiom)
plant:ignore("+ - F")
for k = 0, 7 do
  local l, x, r = k // 4, (k // 2) % 2, k % 2
  plant:rule(string.format("%d < %d > %d -> %s", l, x, r, fig.succ[k + 1]))
end
plant:rule("+ -> -")
plant:rule("- -> +")
plant:iterations(p.n >= 0 and p.n or fig.n)
return plant
