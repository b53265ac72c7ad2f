local img = pge.Image.load("no_such_map.png")
return img
