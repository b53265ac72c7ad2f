local e = pge.Extruder()
e:polygon(4, 1)
e:extrude(1)
e:getPathMatrix():pop()
return e
