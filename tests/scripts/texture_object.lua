-- A material textured by an object with pngBytes() (an image made in the script).
local img = pge.Image.new(4, 4)
img:set(1, 1, "#ff0000")
return pge.mesh{
  positions = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uvs = {0, 0, 1, 0, 0, 1}, indices = {0, 1, 2},
  material = {texture = img:texture(), alpha = "mask"},
}
