-- Honda's monopodial tree (ABOP fig. 2.6, parameters of fig. 2.7a): a trunk A with lateral
-- axes B and C in alternating planes; widths shrink by wr at each branching.
local p = pge.params{
  n = {10, min = 0, max = 14, doc = "derivation steps"},
  r1 = {0.9, min = 0, max = 1, doc = "contraction ratio of the trunk"},
  r2 = {0.6, min = 0, max = 1, doc = "contraction ratio of the branches"},
  a0 = {45, min = 0, max = 180, doc = "branching angle from the trunk"},
  a2 = {45, min = 0, max = 180, doc = "branching angle of lateral axes"},
}

local tree = pge.LSystem("honda")
tree:createInstance(function() return pge.turtle{ sides = 6 } end)
tree:set("r1", p.r1)
tree:set("r2", p.r2)
tree:set("a0", p.a0)
tree:set("a2", p.a2)
tree:set("d", 137.5)   -- divergence angle
tree:set("wr", 0.707)  -- width decrease rate
tree:set("ws", 0.012)  -- the book's widths are pixels: scale to lengths
tree:axiom("A(1,10)")
tree:rule("A(l,w) -> !(w*ws)F(l)[&(a0)B(l*r2,w*wr)]/(d)A(l*r1,w*wr)")
tree:rule("B(l,w) -> !(w*ws)F(l)[-(a2)$C(l*r2,w*wr)]C(l*r1,w*wr)")
tree:rule("C(l,w) -> !(w*ws)F(l)[+(a2)$B(l*r2,w*wr)]B(l*r1,w*wr)")
tree:iterations(p.n)
return tree
