-- A 3D bush (ABOP fig. 1.25): apices A branch in three directions rolled around the axis;
-- segments S grow leaves L (here turtle leaves `~`), colours step with `'`.
local p = pge.params{
  n = {7, min = 0, max = 8, doc = "derivation steps"},
}

local bush = pge.LSystem("bush")
bush:createInstance(function()
  return pge.turtle{ angle = 22.5, width = 0.25, widthFactor = 0.75, sides = 5,
                     colors = {"#5a3d26", "#4a6b2a", "#3f7f2a", "#5c9b33"} }
end)
bush:axiom("A")
bush:rule("A -> [&FL!A]/////'[&FL!A]///////'[&FL!A]")
bush:rule("F -> S/////F")
bush:rule("S -> FL")
bush:rule("L -> ['''^^~(0.6)]")
bush:iterations(p.n)
return bush
