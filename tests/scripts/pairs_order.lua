-- Builds a name in `pairs` order: the same on every run (keys are visited in a defined order).
local t = {}
for _, k in ipairs{"alpha","beta","gamma","delta","epsilon","zeta","eta","theta","iota","kappa"} do t[k] = true end
local s = {}
for k in pairs(t) do s[#s+1] = k end
return pge.mesh{positions={0,0,0,1,0,0,0,1,0}, indices={0,1,2}, name=table.concat(s, ",")}
