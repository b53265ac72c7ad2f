-- A model with an environment map: a 64x32 equirectangular sky made in the script, light
-- blue at the zenith fading to a green-brown ground below the horizon.
local w, h = 64, 32
local sky = pge.Image.new(w, h)
for y = 0, h - 1 do
  local t = y / (h - 1)
  for x = 0, w - 1 do
    if y < h / 2 then
      sky:set(x, y, 0.15 + 0.5 * t, 0.45 + 0.4 * t, 0.95)
    else
      sky:set(x, y, 0.35, 0.3 - 0.1 * t, 0.15)
    end
  end
end
local model = pge.model()
model:add(pge.mesh{
  positions = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1, 0, 1.5, 0},
  indices = {0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0},
  material = {color = "#c8a070"},
})
model:setEnvironment(sky)
return model
