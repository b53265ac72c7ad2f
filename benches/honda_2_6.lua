-- Honda's tree with the parameters of ABOP fig. 2.6 derived 21 steps (14.7 M modules) for
-- `pge derive`, the parametric whole-process row of benches/README.md.
local tree = pge.LSystem("honda")
tree:set("r1", 0.9)
tree:set("r2", 0.7)
tree:set("a0", 45)
tree:set("a2", 45)
tree:set("d", 137.5)
tree:set("wr", 0.707)
tree:axiom("A(1,10)")
tree:rule("A(l,w) -> !(w)F(l)[&(a0)B(l*r2,w*wr)]/(d)A(l*r1,w*wr)")
tree:rule("B(l,w) -> !(w)F(l)[-(a2)$C(l*r2,w*wr)]C(l*r1,w*wr)")
tree:rule("C(l,w) -> !(w)F(l)[+(a2)$B(l*r2,w*wr)]B(l*r1,w*wr)")
tree:iterations(21)
tree:maxModules(100000000)
return tree
