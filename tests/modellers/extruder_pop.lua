local e = pge.Extruder()
e:push()
e:pop()
e:pop()
return e
