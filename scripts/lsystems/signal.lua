-- Signal propagation (ABOP §1.8): an acropetal signal `b` travels up a branching axis one
-- module per step; where it has passed, the segment turns from green to brown (colour 1).
-- Context matching is bracket-aware: the signal enters every branch.
local p = pge.params{
  n = {14, min = 0, max = 60, doc = "derivation steps"},
}

local signal = pge.LSystem("signal")
signal:createInstance(function()
  return pge.turtle{ angle = 30, width = 0.3, sides = 6, colors = {"#4f8a2b", "#6b4a2f"} }
end)
-- The plant: segments `F`, each preceded by a marker: `a` not reached yet, `b` the signal,
-- `c` reached. The signal starts at the base.
signal:axiom("b F a F a F [ + a F a F a F ] a F a F [ - a F a F [ + a F a F ] a F ] a F a F a F")
signal:ignore("F + -")
signal:rule("b < a -> b")
signal:rule("b -> c")
signal:iterations(p.n)
-- Draw: the marker sets the colour of the segment after it.
signal:IRule("b", function() this:setColor(1) return true end)
signal:IRule("c", function() this:setColor(1) return true end)
signal:IRule("a", function() this:setColor(0) return true end)
return signal
