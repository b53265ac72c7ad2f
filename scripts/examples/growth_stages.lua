-- One individual at three stages of its life: the same growth (same parameters, same
-- seed) fed 25, 50 and 90 times, side by side. `pge run species/broadleaf.lua --stages
-- 25,50,90` writes the same three trees as three scenes of one glb.
local species = {
  ratio = 0.6, spread = 0.45, splitsize = 2.5, splitdecay = 0.01,
  directedness = 0.5, localdepth = 2, feed = 1, scale = 0.5, girth = 0.35,
  mesh = { sides = 7, color = "#6b5444" },
  leaves = { perTip = {4, 7}, size = 0.35, maxDepth = 1, colors = {"#356b22", "#86a83a"} },
}

local model = pge.model()
for i, steps in ipairs{25, 50, 90} do
  local options = { steps = steps }
  for k, v in pairs(species) do options[k] = v end
  model:add(pge.Growth(options):model(), pge.mat4.translate(pge.vec3((i - 2) * 9, 0, 0)))
end
return model
