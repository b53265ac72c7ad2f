local img = pge.Image.new(16, 8)
img:set(3, 2, "#ff0000")
local r = img:get(16, 2)
return img
