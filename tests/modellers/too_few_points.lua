local e = pge.Extruder()
e:addPoint2(0, 0)
e:addPoint2(1, 0)
e:extrude(1)
return e
