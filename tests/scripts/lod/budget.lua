-- The budget from a script: never more than the total, nearer instances never fewer leaves.
local d = {}
for i = 1, 2000 do d[i] = (i * 7919) % 1000 * 0.7 end
local counts = pge.lod.budget{ distances = d, leaves = 3000, roots = 40, total = 400000,
                               near = 20, far = 600 }
local sum = 0
for i = 1, #d do
  sum = sum + counts[i]
  for j = 1, #d, 97 do
    if d[i] < d[j] then assert(counts[i] >= counts[j], "nearer got fewer") end
  end
  assert(counts[i] == 0 or (counts[i] >= 40 and counts[i] <= 3000))
  assert(d[i] <= 600 or counts[i] == 0)
end
assert(sum <= 400000, "over budget: " .. sum)
assert(sum >= 390000, "budget not used: " .. sum)
return pge.model()
