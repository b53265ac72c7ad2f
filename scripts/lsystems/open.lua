-- An open L-system (PGE thesis §3.4.3): rewriting reads the instance. Each bud asks the
-- turtle where the interpretation of everything before it left it, and stops growing (turns
-- into a leaf) above a height; below, it grows a segment, a lateral bud and a leader.
local p = pge.params{
  height = {6.0, min = 0.5, max = 100, doc = "buds above this height stop"},
  steps = {14, min = 0, max = 30, doc = "derivation steps"},
}

local plant = pge.LSystem("open")
plant:createInstance(function()
  return pge.turtle{ angle = 32, width = 0.12, widthFactor = 0.8, sides = 6,
                     leaves = {perTip = {1, 2}, size = 0.3} }
end)
plant:axiom{ Bud{ age = 0 } }
plant:RRule("Bud", function(b)
  if this:position().y > p.height then
    return "~(0.5)"
  end
  local child = Bud{ age = b.age + 1 }
  if b.age % 2 == 0 then
    -- A segment, a branch to the side, a roll, and the leader going on.
    return { "!F(0.7)", { "+(40)", Bud{ age = b.age + 1 } }, "/(137.5)", child }
  end
  return { "F(0.5)", "/(90)", child }
end)
plant:iterations(p.steps)
return plant
