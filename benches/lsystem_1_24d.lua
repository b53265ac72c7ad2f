-- ABOP fig. 1.24d derived 14 steps (31 M modules) for `pge derive`, the whole-process
-- L-system row of benches/README.md; its peer is plugins/lsystem/examples/lindenmayer_peer.rs.
local plant = pge.LSystem("fig 1.24d")
plant:axiom("X")
plant:rule("X -> F[+X]F[-X]+X")
plant:rule("F -> FF")
plant:iterations(14)
plant:maxModules(100000000)
return plant
