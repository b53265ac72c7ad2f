-- A stochastic plant (ABOP fig. 1.27): three productions for F with probabilities .33,
-- .33 and .34. Every seed grows a different plant of the same species (`--seed`).
local p = pge.params{
  n = {5, min = 0, max = 8, doc = "derivation steps"},
}

local plant = pge.LSystem("stochastic plant")
plant:createInstance(function()
  return pge.turtle{ angle = 25.7, width = 0.5, sides = 5 }
end)
plant:axiom("F")
plant:rule("F -> F[+F]F[-F]F", 0.33)
plant:rule("F -> F[+F]F", 0.33)
plant:rule("F -> F[-F]F", 0.34)
plant:iterations(p.n)
return plant
