-- A patch of terrain displaced by fBm noise, coloured by height.
local p = pge.params{
  size = {40.0, min = 1, max = 1000, doc = "side of the patch"},
  cells = {96, min = 2, max = 1024, doc = "grid cells per side"},
  height = {6.0, min = 0, max = 200, doc = "height of the hills"},
  frequency = {0.04, min = 0.001, max = 10, doc = "hills per unit length"},
  octaves = {5, min = 1, max = 12, doc = "fBm octaves"},
}

local n = p.cells
local positions, colors, indices = {}, {}, {}
local low, high = {0.18, 0.35, 0.12}, {0.55, 0.5, 0.42}
for j = 0, n do
  for i = 0, n do
    local x = (i / n - 0.5) * p.size
    local z = (j / n - 0.5) * p.size
    local h = pge.noise.fbm(x, z, {octaves = p.octaves, frequency = p.frequency})
    positions[#positions + 1] = x
    positions[#positions + 1] = h * p.height
    positions[#positions + 1] = z
    local t = math.max(0, math.min(1, h * 0.5 + 0.5))
    for k = 1, 3 do colors[#colors + 1] = low[k] + (high[k] - low[k]) * t end
  end
end
for j = 0, n - 1 do
  for i = 0, n - 1 do
    local a = j * (n + 1) + i
    local b, c, d = a + 1, a + n + 1, a + n + 2
    for _, k in ipairs{a, c, b, b, c, d} do indices[#indices + 1] = k end
  end
end
return pge.mesh{positions = positions, colors = colors, indices = indices,
                material = {color = "#ffffff", roughness = 1}, name = "terrain"}
