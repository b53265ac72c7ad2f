-- Standing stones under an evening sky: pge.Image as an environment map
-- (model:setEnvironment). The sky is an equirectangular image made pixel by pixel: row 0 is
-- straight up, the middle row the horizon; the middle column looks along -Z.
local p = pge.params{
  width = {256, min = 8, max = 2048, doc = "sky image width (height is half)"},
  sun = {30, min = -180, max = 180, doc = "sun direction, degrees from -Z towards +X"},
  stones = {9, min = 1, max = 64, doc = "number of stones in the ring"},
}

local w = p.width
local h = w // 2
local sky = pge.Image.new(w, h)
local sun_u = 0.5 + p.sun / 360
local function mix(a, b, t) return a + (b - a) * t end
for y = 0, h - 1 do
  local v = (y + 0.5) / h -- 0 up, 0.5 horizon, 1 down
  for x = 0, w - 1 do
    local r, g, b
    if v < 0.5 then
      local t = (v / 0.5) ^ 3 -- deep blue overhead, orange at the horizon
      r, g, b = mix(0.10, 0.98, t), mix(0.16, 0.62, t), mix(0.42, 0.36, t)
      local du = math.abs((x + 0.5) / w - sun_u)
      du = math.min(du, 1 - du)
      local glow = math.max(0, 1 - math.sqrt((du * 2) ^ 2 + ((0.5 - v) * 3) ^ 2) * 2.5)
      r, g, b = mix(r, 1.0, glow), mix(g, 0.9, glow), mix(b, 0.6, glow)
    else
      local t = (v - 0.5) / 0.5 -- dusky ground
      r, g, b = mix(0.28, 0.12, t), mix(0.22, 0.10, t), mix(0.16, 0.08, t)
    end
    sky:set(x, y, r, g, b)
  end
end

local box = require("lib.box")
local model = pge.model()
for i = 0, p.stones - 1 do
  local angle = i / p.stones * 360
  local tall = 1.6 + pge.random() * 1.2
  model:add(box.mesh("#8a8378"),
    pge.mat4.rotate({0, 1, 0}, angle)
    * pge.mat4.translate{4, tall / 2, 0}
    * pge.mat4.scale{0.5, tall, 0.9})
end
model:setEnvironment(sky)
return model
