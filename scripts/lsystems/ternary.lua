-- A ternary branching tree with tropism (ABOP fig. 2.8a): three branches at each apex,
-- segments elongating and thickening with age, bent down by gravity (T = (0,-1,0)).
local p = pge.params{
  n = {6, min = 0, max = 8, doc = "derivation steps"},
  elasticity = {0.22, min = 0, max = 1, doc = "susceptibility to tropism"},
}

local tree = pge.LSystem("ternary")
tree:createInstance(function()
  return pge.turtle{ tropism = {0, -1, 0}, elasticity = p.elasticity, sides = 6,
                     leaves = {perTip = {2, 4}, size = 0.35} }
end)
tree:set("d1", 94.74)   -- divergence angle 1
tree:set("d2", 132.63)  -- divergence angle 2
tree:set("a", 18.95)    -- branching angle
tree:set("lr", 1.109)   -- elongation rate
tree:set("vr", 1.732)   -- width increase rate
tree:set("s", 0.02)     -- the book's lengths and widths are pixels: scale them
tree:declare("W")
-- W(w) is the width command `!` of the book, kept as its own module so it can grow.
tree:axiom("W(1)F(200)/(45)A")
tree:rule("A -> W(vr)F(50)[&(a)F(50)A]/(d1)[&(a)F(50)A]/(d2)[&(a)F(50)A]")
tree:rule("F(l) -> F(l*lr)")
tree:rule("W(w) -> W(w*vr)")
tree:iterations(p.n)
tree:interpretEveryStep(false)
-- Lengths and widths in the book's units, drawn scaled.
tree:IRule("F", function(f) this:forward(f[1] * 0.02) return true end)
tree:IRule("W", function(w) this:setWidth(w[1] * 0.02) return true end)
return tree
