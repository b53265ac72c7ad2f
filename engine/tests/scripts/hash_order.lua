-- A model whose vertex order is the order `pairs` and `next` visit keys in: string keys
-- (hashed with Lua's per-state seed), numbers, booleans. Without a defined traversal order
-- its bytes would change from one process (or one Lua state) to the next.
local t = {}
for i = 1, 300 do t["key" .. i] = i end
t[0.5], t[-7], t[true], t[false] = 301, 302, 303, 304
local positions, order = {}, {}
for k, v in pairs(t) do
  order[#order + 1] = tostring(k)
  positions[#positions + 1] = v
  positions[#positions + 1] = #order
  positions[#positions + 1] = 0
end
local k, v = next(t)
while k ~= nil do
  positions[#positions + 1] = v
  positions[#positions + 1] = 0
  positions[#positions + 1] = #positions
  k, v = next(t, k)
end
local indices = {}
for i = 0, #positions // 3 - 3, 3 do
  indices[#indices + 1] = i
  indices[#indices + 1] = i + 1
  indices[#indices + 1] = i + 2
end
return pge.mesh{ positions = positions, indices = indices, name = table.concat(order, ",", 1, 12) }
